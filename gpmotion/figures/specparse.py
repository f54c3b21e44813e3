"""Parsing helpers shared by the planar (gpmotion.figures.spec) and the 3-D
(gpmotion.figures.spec3d) figure compilers: checked numbers and vectors, the
body list, the joint tree, the ground table."""
from __future__ import annotations

import math

import networkx as nx
import numpy as np

from ..model import Figure


class SpecError(ValueError):
    """A figure spec is malformed or impossible; the message names the field."""


PLANAR_AXIS = (0.0, -1.0, 0.0)   # CCW in the x–z plane seen with x right, z up


GROUND_KEYS = ("k_ground", "c_ground", "mu", "k_tangent", "c_tangent", "max_contacts")


def check_ground(spec: dict, planar: bool = True) -> None:
    """A spec's optional ``[ground]``: positive numbers for make_scene's ground
    keys (``mu`` may be 0; ``max_contacts`` an integer >= 0, planar figures only)."""
    g = spec.get("ground", {})
    if not isinstance(g, dict):
        raise SpecError("ground: must be a table of " + ", ".join(GROUND_KEYS))
    for k in g:
        if k not in GROUND_KEYS:
            raise SpecError(f"ground: unknown key {k!r}; known: {', '.join(GROUND_KEYS)}")
        if k == "max_contacts":
            v = g[k]
            if isinstance(v, bool) or not isinstance(v, int) or v < 0:
                raise SpecError(f"ground: 'max_contacts' must be an integer >= 0 (0: every point), got {v!r}")
            if v and not planar:
                raise SpecError("ground: 'max_contacts' applies to planar figures only")
            continue
        _num(g, k, "ground", positive=k != "mu", lo=0.0)


def _num(d, key, where, default=None, lo=None, positive=False):
    v = d.get(key, default)
    if v is None:
        raise SpecError(f"{where}: missing '{key}'")
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise SpecError(f"{where}: '{key}' must be a finite number, got {v!r}")
    if positive and v <= 0:
        raise SpecError(f"{where}: '{key}' must be > 0, got {v!r}")
    if lo is not None and v < lo:
        raise SpecError(f"{where}: '{key}' must be >= {lo}, got {v!r}")
    return float(v)


def _vec(d, key, where, n, default=None):
    v = d.get(key, default)
    if v is None:
        raise SpecError(f"{where}: missing '{key}'")
    if (not isinstance(v, (list, tuple)) or len(v) != n or
            not all(isinstance(x, (int, float)) and not isinstance(x, bool)
                    and math.isfinite(x) for x in v)):
        raise SpecError(f"{where}: '{key}' must be a list of {n} finite numbers, got {v!r}")
    return np.array(v, dtype=np.float64)


def body_segment(b, i, dims):
    """(where, mass, a, b, radius, com) of a body entry: its name, mass, capsule and centre of mass."""
    where = f"body {b.get('name', i)!r}"
    if not isinstance(b.get("name"), str) or not b["name"]:
        raise SpecError(f"body #{i}: needs a 'name'")
    mass = _num(b, "mass", where, positive=True)
    seg = b.get("segment")
    if not isinstance(seg, list) or len(seg) != 2:
        form = "[[x0, z0], [x1, z1]]" if dims == 2 else "[[x0, y0, z0], [x1, y1, z1]]"
        raise SpecError(f"{where}: 'segment' must be {form}")
    a = _vec({"a": seg[0]}, "a", where + " segment", dims)
    bb = _vec({"b": seg[1]}, "b", where + " segment", dims)
    radius = _num(b, "radius", where, default=0.02, positive=True)
    com = _vec(b, "com", where, dims, default=list((a + bb) / 2))
    return where, mass, a, bb, radius, com


def servo_arrays(act) -> dict:
    """kp, kd, tau_max and neutral of the actuated dofs ``act`` [(index, dof dict)]: Model fields."""
    return {k: np.array([d[k] for _, d in act], dtype=np.float64)
            for k in ("kp", "kd", "tau_max", "neutral")}


def limit_gains(spec: dict) -> dict:
    """The joint-limit spring's stiffness and damping (``[limits]``): Model fields."""
    limits = spec.get("limits", {})
    return dict(limit_k=_num(limits, "stiffness", "limits", default=30.0, positive=True),
                limit_c=_num(limits, "damping", "limits", default=0.5, lo=0.0))


def figure_of(spec, model, dims, *, links, sites, body_link, **fields):
    """The Figure of a compiled model: names, sites (all, sensed or not) and the spec."""
    return Figure(
        model=model, link_names=[L["name"] for L in links],
        site_names=[s[0] for s in sites],
        site_link=np.array([body_link[s[1]] for s in sites], dtype=np.int64),
        site_pos=np.array([s[2] for s in sites], dtype=np.float64).reshape(-1, dims),
        description=str(spec.get("description", "")), spec=spec, **fields)


def joint_where(j, bodies, i) -> str:
    """A joint entry's name for messages, once its names and bodies are checked."""
    where = f"joint {j.get('name', i)!r}"
    for k in ("name", "parent", "child"):
        if not isinstance(j.get(k), str):
            raise SpecError(f"{where}: needs '{k}' (a name)")
    for k in ("parent", "child"):
        if j[k] not in bodies:
            raise SpecError(f"{where}: unknown {k} body {j[k]!r}")
    return where


def parse_points(items, kind, bodies, dims, sensed_sites):
    """Named points on bodies (contacts, sites): [(name, body, position, sense)].

    ``sense`` (sites only, and only where ``sensed_sites``) puts the site's position in the senses.
    """
    out = []
    if not isinstance(items, list):
        raise SpecError(f"{kind}s must be a list of tables")
    for i, p in enumerate(items):
        if not isinstance(p, dict):
            raise SpecError(f"{kind} #{i}: must be a table")
        where = f"{kind} {p.get('name', i)!r}"
        if not isinstance(p.get("name"), str) or p.get("body") not in bodies:
            raise SpecError(f"{where}: needs a 'name' and a known 'body'")
        sense = p.get("sense", False)
        if "sense" in p and not (kind == "site" and sensed_sites):
            raise SpecError(f"{where}: only sites of 3-D figures take 'sense'")
        if not isinstance(sense, bool):
            raise SpecError(f"{where}: 'sense' must be true or false")
        out.append((p["name"], p["body"], _vec(p, "position", where, dims), sense))
    names = [p[0] for p in out]
    if len(set(names)) != len(names):
        raise SpecError(f"{kind} names must be unique: {names}")
    return out


def _body(b, i):
    where, mass, a, bb, radius, com = body_segment(b, i, 2)
    length = float(np.hypot(*(bb - a)))
    shape = b.get("shape", "rod")
    if "inertia" in b:
        inertia = _num(b, "inertia", where, positive=True)
    elif shape == "rod":
        inertia = mass * length ** 2 / 12.0
    elif shape == "box":
        inertia = mass * (length ** 2 + (2 * radius) ** 2) / 12.0
    else:
        raise SpecError(f"{where}: unknown shape {shape!r} (rod, box)")
    inertia = max(inertia, mass * radius ** 2 / 2.0)  # a capsule is never thinner than its radius
    return dict(name=b["name"], mass=mass, com=com, inertia=inertia,
                seg=(a, bb), radius=radius)


def _tree_order(spec_bodies, joints, root_body):
    g = nx.DiGraph()
    g.add_nodes_from(spec_bodies)
    for j in joints:
        if g.has_edge(j["parent"], j["child"]) or g.in_degree(j["child"]) > 0:
            raise SpecError(f"joint {j['name']!r}: body {j['child']!r} already has a parent")
        g.add_edge(j["parent"], j["child"], joint=j)
    if root_body not in g:
        raise SpecError(f"root: unknown body {root_body!r}")
    if not nx.is_arborescence(g) or g.in_degree(root_body) != 0:
        loose = set(g) - {root_body} - set(nx.descendants(g, root_body))
        raise SpecError("joints must form a tree rooted at the root body"
                        + (f"; not reached from it: {sorted(loose)}" if loose else "; a cycle exists"))
    return [g.edges[p, c]["joint"] for p, c in nx.dfs_edges(g, root_body)]


MAX_NAME = 200


TOP_KEYS = ("name", "description", "extends", "dimensions", "root", "bodies", "joints",
            "contacts", "sites", "ground", "limits")


def check_top_keys(spec: dict) -> None:
    """A figure file's top-level keys are the ones a figure has: a misspelt one
    (``gravty = -1.0``) is refused, never silently ignored."""
    unknown = sorted(str(k) for k in spec if k not in TOP_KEYS)
    if unknown:
        from ..names import did_you_mean
        raise SpecError(f"figure: unknown top-level key(s) {', '.join(map(repr, unknown))}"
                        f"{did_you_mean(unknown[0], TOP_KEYS)}; known: {', '.join(TOP_KEYS)}")


def _name_and_bodies(spec: dict, parse_body):
    """The figure's name, its raw [[bodies]] list and the parsed bodies by name
    (shared by the planar and the 3-D compilers; ``parse_body(b, i)`` differs)."""
    check_top_keys(spec)
    name = spec.get("name")
    if not isinstance(name, str) or not name:
        raise SpecError("figure: needs a 'name'")
    if len(name) > MAX_NAME:          # a name is drawn in titles: a huge one stalls rendering
        raise SpecError(f"figure: 'name' is {len(name):,} characters; at most {MAX_NAME}")
    raw_bodies = spec.get("bodies")
    if not isinstance(raw_bodies, list) or not raw_bodies:
        raise SpecError(f"figure {name!r}: needs at least one [[bodies]] entry")
    bodies = {}
    for i, b in enumerate(raw_bodies):
        if not isinstance(b, dict):
            raise SpecError(f"body #{i}: must be a table")
        bd = parse_body(b, i)
        if bd["name"] in bodies:
            raise SpecError(f"body {bd['name']!r} is defined twice")
        bodies[bd["name"]] = bd
    return name, raw_bodies, bodies
