"""A scene's meshes and lights as a notebook reads them: lists (in file order, as the compiler and
the readers use them) that also answer by name, as a mapping does (keys(), items(), values(),
`name in`, `[name]`), and say in one line what they hold rather than dumping their arrays."""

from pathtrace.errors import UserError, short


def vector(v) -> str:
    """A 3-vector for a repr: '(0, 1.5, -2)'."""
    return "(" + ", ".join(f"{float(x):.4g}" for x in v) + ")"


def own_name(i: int, item) -> str:
    return item.name


def name_and_index(i: int, item) -> str:
    """The name of a thing that has none of its own: its type's and its index, "point 2"."""
    return f"{item.name} {i}"


class NamedList(list):
    """A list of named things: `key(i, item)` gives each one's name (a mesh's own, or a light's
    type and index where lights have none). Indexing by number and iteration are a list's; a
    string indexes by name."""

    def __init__(self, items=(), key=None, kind=("entry", "entries")):
        super().__init__(items)
        self._key = key or own_name
        self._kind = kind              # (singular, plural), for messages and the repr

    def keys(self) -> list:
        return [self._key(i, item) for i, item in enumerate(self)]

    def values(self) -> list:
        return list(self)

    def items(self) -> list:
        return list(zip(self.keys(), self))

    def __getitem__(self, key):
        if isinstance(key, str):
            for name, item in self.items():
                if name == key:
                    return item
            raise UserError(f"no {self._kind[0]} named {short(key)} (named: {summary(self.keys())})")
        return super().__getitem__(key)

    def __contains__(self, key) -> bool:
        return key in self.keys() if isinstance(key, str) else super().__contains__(key)

    def __repr__(self) -> str:
        return f"<{len(self)} {self._kind[len(self) != 1]}" + (f": {summary(self.keys())}>" if len(self) else ">")


def summary(names, limit: int = 8) -> str:
    """The first `limit` names, and how many more."""
    names = [str(n) for n in names]
    more = len(names) - limit
    return ", ".join(names[:limit]) + (f", ... ({more} more)" if more > 0 else "") if names else "none"
