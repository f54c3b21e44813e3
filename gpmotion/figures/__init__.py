"""Figure registry: shipped TOML specs by name, user specs by path or dict.

Compiled figures are cached by name or path, and every caller gets its own
deep copy: a Figure holds mutable arrays (its Model, ``q_default``...), and
one task changing its copy must not change every other task's figure.
"""
from __future__ import annotations

import copy
from pathlib import Path

from ..model import Figure
from .spec import SpecError, compile_spec, load_spec, merge_spec
from .spec3d import compile_spec3d, planar_spec_to_3d

_HERE = Path(__file__).parent
_REGISTRY: dict[str, Path | dict] = {p.stem: p for p in sorted(_HERE.glob("*.toml"))}
_CACHE: dict[str, Figure] = {}


def register_figure(name: str, spec: dict | str | Path) -> None:
    """Register a figure spec (dict or TOML path) under ``name``; registering
    the same TOML file again is harmless, another spec under a taken name is an error."""
    new = spec if isinstance(spec, dict) else Path(spec).resolve()
    old = _REGISTRY.get(name)
    if old is not None:
        if isinstance(old, Path) and old.resolve() == new:
            return
        raise ValueError(f"figure {name!r} is already registered ({old if isinstance(old, Path) else 'a spec dict'}); "
                         f"{new if isinstance(new, Path) else 'a spec dict'} needs another name")
    _REGISTRY[name] = new


def figure_names() -> list[str]:
    return sorted(_REGISTRY)


def resolve_spec(spec: dict, _seen=()) -> dict:
    """A spec with its ``extends = "figure"`` chain merged in (``merge_spec``)."""
    base = spec.get("extends")
    if base is None:
        return spec
    if not isinstance(base, str) or base not in _REGISTRY:
        from ..names import unknown
        raise SpecError(f"extends: {unknown('figure', base, figure_names())}")
    if base in _seen:
        raise SpecError(f"extends: figures extend each other in a loop: {' -> '.join(_seen + (base,))}")
    src = _REGISTRY[base]
    parent = resolve_spec(src if isinstance(src, dict) else load_spec(src), _seen + (base,))
    return merge_spec(parent, spec)


def load_figure(name_or_spec) -> Figure:
    """A compiled Figure from a registered name, a TOML path, or a spec dict
    (a spec may start from another figure: ``extends = "herman"``)."""
    if isinstance(name_or_spec, Figure):
        return name_or_spec
    if isinstance(name_or_spec, dict):
        return compile_spec(resolve_spec(name_or_spec))
    key = str(name_or_spec)
    if key in _CACHE:
        return copy.deepcopy(_CACHE[key])
    if key in _REGISTRY:
        src = _REGISTRY[key]
        fig = compile_spec(resolve_spec(src if isinstance(src, dict) else load_spec(src), (key,)))
    elif key.endswith(".toml") or Path(key).exists():
        fig = compile_spec(resolve_spec(load_spec(key)))
    else:
        from ..names import unknown
        raise SpecError(unknown("figure", key, figure_names()))
    _CACHE[key] = fig
    return copy.deepcopy(fig)


__all__ = ["SpecError", "compile_spec", "compile_spec3d", "load_spec", "load_figure", "merge_spec",
           "resolve_spec",
           "planar_spec_to_3d", "register_figure", "figure_names"]
