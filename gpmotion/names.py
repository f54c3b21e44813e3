"""Name suggestions for error messages ("did you mean 'elbow'?")."""
from __future__ import annotations

import difflib
from typing import Iterable


def suggest(word: str, choices: Iterable[str]) -> str | None:
    """The closest of ``choices`` to ``word``, or None when nothing is close."""
    close = difflib.get_close_matches(str(word), [str(c) for c in choices], n=1, cutoff=0.6)
    return close[0] if close else None


def did_you_mean(word: str, choices: Iterable[str]) -> str:
    """`` (did you mean 'x'?)`` for the closest choice, or '' (append to a message)."""
    best = suggest(word, choices)
    return f" (did you mean {best!r}?)" if best else ""


def unknown(kind: str, word: str, choices: Iterable[str]) -> str:
    """One line: ``unknown task 'lamp_hopp' (did you mean 'lamp_hop'?); known: a, b``."""
    choices = sorted(choices)
    return f"unknown {kind} {word!r}{did_you_mean(word, choices)}; known: {', '.join(choices)}"
