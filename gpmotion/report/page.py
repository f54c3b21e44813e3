"""The report page: one self-contained HTML file (the vendored libraries, the
player and the data inlined; nothing fetched when it opens)."""
from __future__ import annotations

import html
import json
import math
import re
from importlib import resources

from ..version import __version__

_ORBIT_IMPORT_END = "} from 'three';"


def _asset(*parts: str) -> str:
    return resources.files(__package__).joinpath(*parts).read_text(encoding="utf-8")


def orbit_controls() -> str:
    """three.js's OrbitControls (an ES module) as a classic script: its one
    ``import {…} from 'three'`` reads the names from the global THREE, its
    ``export`` becomes THREE.OrbitControls."""
    src = _asset("vendor", "three", "OrbitControls.js")
    head, sep, body = src.partition(_ORBIT_IMPORT_END)
    names = head.strip()
    if not sep or not names.startswith("import {") or "export { OrbitControls };" not in body:
        raise RuntimeError("vendored OrbitControls.js is not the expected r159 module")
    names = names[len("import {"):].replace("\n", " ").replace("\t", " ")
    body = body.replace("export { OrbitControls };", "THREE.OrbitControls = OrbitControls;")
    return f"(function () {{\nconst {{{names}}} = THREE;\n{body}\n}})();"


def _clean(x):
    """JSON-safe: non-finite floats become null."""
    if isinstance(x, float):
        return x if math.isfinite(x) else None
    if isinstance(x, dict):
        return {str(k): _clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_clean(v) for v in x]
    if hasattr(x, "item") and not hasattr(x, "__len__"):
        return _clean(x.item())
    return x


def _script_text(s: str) -> str:
    """Text safe inside a <script> element: nothing in it can close the element
    or open an HTML comment (in JavaScript strings and regular expressions
    ``<\\/`` and ``<\\!`` mean the same)."""
    return re.sub(r"<(/script|!--)", lambda m: "<\\" + m.group(1), s, flags=re.IGNORECASE)


def page(data: dict, title: str) -> str:
    """The HTML of a report of ``data`` (the dict gpmotion.report.sources builds)."""
    payload = json.dumps(_clean(data), separators=(",", ":"), allow_nan=False)
    parts = {
        "@@TITLE@@": html.escape(title),
        "@@VERSION@@": html.escape(__version__),
        "@@UPLOT_CSS@@": _asset("vendor", "uplot", "uPlot.min.css"),
        "@@CSS@@": _asset("report.css"),
        "@@DATA@@": payload.replace("<", "\\u003c"),      # JSON.parse reads it back
        "@@THREE@@": _script_text(_asset("vendor", "three", "three.min.js")),
        "@@ORBIT@@": _script_text(orbit_controls()),
        "@@UPLOT@@": _script_text(_asset("vendor", "uplot", "uPlot.iife.min.js")),
        "@@PLAYER@@": _script_text(_asset("player.js")),
    }
    return re.sub(r"@@[A-Z_]+@@", lambda m: parts[m.group(0)], _asset("template.html"))
