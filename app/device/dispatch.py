"""The kernels' dispatch over a registry's kinds (BSDFs, lights), generated: a switch on a kind's
tag, and in a generic program the commonest kind tested first (kernels/inlining.h: DISPATCH)."""


def switch_body(tag: str, cases: dict, default: str) -> str:
    """A function's body that switches on the expression `tag` over `cases` (a kind's tag
    constant -> the call that handles it), returning `default` for the others."""
    switch = "".join(f"    case {label}: return {call};\n" for label, call in cases.items())
    return f"{{\n    switch ({tag}) {{\n{switch}    default: return {default};\n    }}\n}}\n"


def dispatch_glue(signature: str, tag: str, cases: dict, default: str, fast: str = None) -> str:
    """The kernel function `signature`, marked DISPATCH (kernels/inlining.h: a call in a generic
    program on a GPU), whose body is switch_body's. With `fast`, one
    of those constants, a generic program tests it first and runs its call inlined, calling the
    switch (renamed ..._by_switch) for the rest: the commonest kind then makes no call. A scene's
    own program compiles the #else, the switch alone."""
    body = switch_body(tag, cases, default)
    if fast not in cases:
        return f"DISPATCH {signature}\n{body}"
    name = signature.split("(")[0].split()[-1]
    arguments = ", ".join(a.split()[-1].lstrip("*") for a in signature[:-1].split("(", 1)[1].split(","))
    return (f"#ifdef GENERIC\nDISPATCH {signature.replace(name + '(', name + '_by_switch(')}\n{body}"
            f"{signature}\n{{\n    if ({tag} == {fast})\n        return {cases[fast]};\n"
            f"    return {name}_by_switch({arguments});\n}}\n#else\nDISPATCH {signature}\n{body}#endif\n")
