"""The case files shipped with wearcheck, found by name.

A shipped case is a ``NAME.toml`` beside this module. Its first line is a
comment that describes it in one sentence (``wearcheck cases`` lists it).
"""

from __future__ import annotations

from pathlib import Path

from .errors import CaseError

#: the folder holding the shipped case files
SHIPPED_DIR = Path(__file__).resolve().parent


def shipped_cases() -> dict[str, Path]:
    """Name -> path of every shipped case, sorted by name."""
    return {p.stem: p for p in sorted(SHIPPED_DIR.glob("*.toml"), key=lambda p: p.stem)}


def shipped(name: str) -> Path:
    """Path of the shipped case called ``name``.

    ``"paper"``, ``"paper.toml"`` and an unambiguous start such as ``"pap"`` all
    name ``paper.toml``; an unknown or ambiguous name is a ``CaseError`` that
    lists the shipped names.
    """
    found = _by_name(name)
    if found is None:
        raise CaseError(f"no shipped case '{name}'; shipped: " + ", ".join(shipped_cases())
                        + " ('wearcheck cases' describes them)")
    return found


def _by_name(name: str) -> Path | None:
    """The shipped case ``name`` names exactly or by an unambiguous start; None if
    none does; ``CaseError`` if several start with it."""
    available = shipped_cases()
    stem = name.removesuffix(".toml")
    if stem in available:
        return available[stem]
    matches = [n for n in available if stem and n.startswith(stem)]
    if len(matches) > 1:
        raise CaseError(f"case '{name}' is ambiguous: it starts the shipped cases "
                        + ", ".join(matches) + "; give the full name")
    return available[matches[0]] if matches else None


def describe(path: str | Path) -> str:
    """The one-line description of a case file: its first comment line (editor
    directives such as ``#:schema ...`` skipped)."""
    for line in Path(path).read_text(encoding="utf-8-sig").splitlines():
        line = line.strip()
        if not line or line.startswith("#:"):
            continue
        return line.lstrip("#").strip() if line.startswith("#") else ""
    return ""


def resolve(name_or_path: str | Path) -> Path:
    """The case file a command line names: an existing path, else a shipped case.

    A path that exists is taken as it is (``cases.load`` then checks it). Anything
    else must be the name of a shipped case, or the unambiguous start of one
    (``pap`` for ``paper``); an unknown or ambiguous name is a ``CaseError``
    that lists the shipped names.
    """
    path = Path(name_or_path)
    if path.exists():
        return path
    text = str(name_or_path)
    available = shipped_cases()
    listing = ", ".join(available)
    looks_like_a_name = text and path.name == text and not text.startswith(".")
    if text == "-":
        raise CaseError("case '-': wearcheck does not read a case from standard input; save "
                        f"it to a file and give its path, or name a shipped case: {listing}")
    if not looks_like_a_name:
        raise CaseError(f"case file '{text}' does not exist (shipped cases, by name: {listing})")
    found = _by_name(text)
    if found is not None:
        return found
    raise CaseError(f"case '{text}' is neither a file nor a shipped case; shipped: {listing} "
                    "('wearcheck cases' describes them)")
