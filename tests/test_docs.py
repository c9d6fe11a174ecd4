"""The documents and comments say what the code is: every repository path they name (app/...,
kernels/..., docs/..., and the rest) exists, every Markdown link between the documents reaches
its file and heading, and every module or attribute named as pathtrace.x.y (or app.x.y)
imports."""

import importlib
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
FOLDERS = ("app", "kernels", "shaders", "tests", "docs", "assets", "examples", "scripts")
PATH = re.compile(r"(?<![\w./-])((?:" + "|".join(FOLDERS) + r")/[\w./*-]*[\w*])")
MODULE = re.compile(r"(?<![\w./-])(?:pathtrace|app)((?:\.[a-z_][a-z0-9_]*)+)")


def texts():
    """The documents, and every source file's text (comments and docstrings name paths too)."""
    files = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md")), ROOT / "assets" / "README.md"]
    for folder in ("app", "kernels", "shaders", "tests", "scripts", "examples", "docs/notes/studies"):
        files += sorted(f for f in (ROOT / folder).rglob("*") if f.suffix in (".py", ".cl", ".h", ".frag", ".vert"))
    return [(f, f.read_text(encoding="utf-8")) for f in files]


def named_paths():
    for f, text in texts():
        for m in PATH.finditer(text):
            path = m.group(1).rstrip(".")
            if f.name == "test_docs.py":
                continue
            yield f.relative_to(ROOT).as_posix(), path


def test_every_path_named_exists():
    missing = sorted({(where, path) for where, path in named_paths()
                      if not (any(ROOT.glob(path)) if "*" in path else (ROOT / path).exists())})
    assert not missing, missing


LINK = re.compile(r"\]\(([^)\s#]+\.md)?(?:#([^)\s]+))?\)")


def anchors(path: Path) -> set:
    """The anchors GitHub gives a Markdown file's headings: lower case, punctuation but hyphens
    dropped, spaces made hyphens, a repeated one numbered."""
    found, seen = set(), {}
    for line in path.read_text(encoding="utf-8").splitlines():
        if re.match(r"#{1,6} ", line):
            slug = re.sub(r"[^\w\- ]", "", line.lstrip("#").strip().lower()).replace(" ", "-")
            found.add(slug if slug not in seen else f"{slug}-{seen[slug]}")
            seen[slug] = seen.get(slug, 0) + 1
    return found


def test_every_link_between_documents_reaches_its_heading():
    bad = []
    for f, text in texts():
        if f.suffix != ".md":
            continue
        for m in LINK.finditer(text):
            target = (f.parent / m.group(1)).resolve() if m.group(1) else f
            if not target.exists() or (m.group(2) and m.group(2) not in anchors(target)):
                bad.append((f.relative_to(ROOT).as_posix(), m.group(0)))
    assert not bad, bad


def resolves(dotted: str) -> bool:
    """pathtrace.a.b.c: the longest importable module prefix (the package itself at least), then
    attributes."""
    parts = dotted.split(".")
    for k in range(len(parts), -1, -1):
        try:
            obj = importlib.import_module(".".join(["pathtrace", *parts[:k]]))
        except ImportError:
            continue
        for name in parts[k:]:
            if not hasattr(obj, name):
                return False
            obj = getattr(obj, name)
        return True
    return False


def test_every_module_named_imports():
    bad = set()
    for f, text in texts():
        if "tests" in f.relative_to(ROOT).parts:     # tests name missing attributes on purpose
            continue
        for m in MODULE.finditer(text):
            dotted = m.group(1)[1:]
            if dotted.split(".")[-1] in ("py", "cl", "md", "toml", "json", "png", "exr"):
                continue                      # a file name, checked above
            if not resolves(dotted):
                bad.add((f.relative_to(ROOT).as_posix(), m.group(0)))
    assert not bad, sorted(bad)


@pytest.mark.parametrize("command", ["render", "view", "convert"])
def test_help_names_every_built_in_scene(command, capsys):
    from pathtrace.cli.main import build_parser
    from pathtrace.scene.builtin import BUILTIN_SCENES
    with pytest.raises(SystemExit):
        build_parser().parse_args([command, "--help"])
    text = " ".join(capsys.readouterr().out.split())
    for name in BUILTIN_SCENES:
        assert name in text, name
