"""Figure specs (TOML files or dicts) → validated, compiled :class:`Figure`.

A spec names bodies, the joints between them, contact points and sites.
Body frames: a body's origin is the joint that attaches it to its parent
(the root body's origin is its placement); geometry (``segment``, ``com``)
is given in that frame, x along the body, z across it.  Inertia is either
given or derived from ``shape`` ("rod": thin rod along the segment, "box":
segment length × 2·radius) about the centre of mass.

A variant of a registered figure is a small spec with ``extends = "herman"``:
it lists only what differs (``merge_spec``: tables merge; bodies, joints,
contacts and sites update by ``name`` or append).
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..model import REVOLUTE, SLIDE_X, SLIDE_Z, Figure, Model
from ..sim.senses import sense_layout
from .spec3d import compile_spec3d
from .specparse import (PLANAR_AXIS, SpecError, _body,  # noqa: F401 (SpecError: re-exported)
                        _name_and_bodies, _num, _tree_order, _vec, check_ground, figure_of, joint_where,
                        limit_gains, parse_points, servo_arrays)

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib


def load_spec(path: str | Path) -> dict:
    from ..records import FormatError, read_text
    from .specparse import check_top_keys
    path = Path(path)
    if not path.exists():
        raise SpecError(f"{path}: no such figure file")
    try:                         # a regular UTF-8 file (a FIFO or binary: one line)
        spec = tomllib.loads(read_text(path, 1 << 20))
        check_top_keys(spec)
        return spec
    except FormatError as e:
        raise SpecError(str(e)) from None
    except SpecError as e:
        raise SpecError(f"{path}: {e}") from None
    except tomllib.TOMLDecodeError as e:
        raise SpecError(f"{path}: not valid TOML ({e})") from None


NAMED_LISTS = ("bodies", "joints", "contacts", "sites")
# keys without which an extending spec's entry cannot be new: a name it does
# not find in the base is then a typo, not an addition
_NEW_ENTRY_KEYS = {"bodies": ("mass",), "joints": ("parent", "child"), "contacts": ("body",),
                   "sites": ("body",)}
def merge_spec(base: dict, over: dict) -> dict:
    """``over`` laid on ``base`` (what ``extends = "figure"`` does): tables merge
    key by key; in the named lists (bodies, joints, contacts, sites) an entry
    whose ``name`` exists updates that entry, a new name is appended; any
    other value replaces the base's.  Neither input is modified."""
    out = dict(base)
    for key, value in over.items():
        if key == "extends":
            continue
        old = out.get(key)
        if key in NAMED_LISTS and isinstance(old, list) and isinstance(value, list):
            merged = [dict(x) if isinstance(x, dict) else x for x in old]
            index = {x.get("name"): i for i, x in enumerate(merged) if isinstance(x, dict)}
            for item in value:
                if not isinstance(item, dict) or not isinstance(item.get("name"), str):
                    raise SpecError(f"{key}: every entry of an extending spec needs a 'name'")
                if item["name"] in index:
                    merged[index[item["name"]]].update(item)
                elif any(k not in item for k in _NEW_ENTRY_KEYS[key]):
                    raise SpecError(_no_such_entry(key, item["name"], index, base))
                else:
                    index[item["name"]] = len(merged)
                    merged.append(dict(item))
            out[key] = merged
        elif isinstance(old, dict) and isinstance(value, dict):
            out[key] = {**old, **value}
        else:
            out[key] = value
    return out


def _no_such_entry(key: str, name: str, known, base: dict) -> str:
    from ..names import did_you_mean
    kind = "body" if key == "bodies" else key[:-1]
    hint = did_you_mean(name, [k for k in known if isinstance(k, str)])
    return (f"no such {kind} {name!r} in {base.get('name', 'the base figure')}{hint}; a new {kind} "
            f"needs {' and '.join(repr(k) for k in _NEW_ENTRY_KEYS[key])}")


def _joint(j, bodies, i):
    where = joint_where(j, bodies, i)
    if j.get("type", "hinge") != "hinge":
        raise SpecError(f"{where}: unknown joint type {j.get('type')!r} (the planar kernel has 'hinge')")
    axis = tuple(_vec(j, "axis", where, 3, default=list(PLANAR_AXIS)))
    if axis != PLANAR_AXIS:
        raise SpecError(f"{where}: planar figures need axis {list(PLANAR_AXIS)} (x–z plane, CCW), got {list(axis)}")
    lim = _vec(j, "limits", where, 2, default=[-math.pi, math.pi])
    if not lim[0] < lim[1]:
        raise SpecError(f"{where}: limits must be [lo, hi] with lo < hi, got {list(lim)}")
    neutral = _num(j, "neutral", where, default=0.0)
    if not lim[0] <= neutral <= lim[1]:
        raise SpecError(f"{where}: neutral {neutral} lies outside limits {list(lim)}")
    actuated = j.get("actuated", True)
    if not isinstance(actuated, bool):
        raise SpecError(f"{where}: 'actuated' must be true or false")
    return dict(name=j["name"], parent=j["parent"], child=j["child"],
                offset=_vec(j, "offset", where, 2, default=[0.0, 0.0]),
                angle=_num(j, "angle", where, default=0.0), lo=lim[0], hi=lim[1],
                neutral=neutral, initial=_num(j, "initial", where, default=neutral),
                actuated=actuated, kp=_num(j, "kp", where, default=0.0, lo=0.0),
                kd=_num(j, "kd", where, default=0.0, lo=0.0),
                tau_max=_num(j, "torque_limit", where, default=0.0, lo=0.0),
                damping=_num(j, "damping", where, default=0.0, lo=0.0))


def _points(items, kind, bodies):
    return [(n, b, x) for n, b, x, _ in parse_points(items, kind, bodies, 2, sensed_sites=False)]


def compile_spec(spec: dict, sense_ranges=None) -> Figure:
    """Validate a spec dict and compile it into a Figure (arrays parents-first)."""
    if not isinstance(spec, dict):
        raise SpecError("a figure spec must be a table/dict")
    # ---- 3-D figures: `dimensions = 3` specs compile in spec3d ----
    dims = spec.get("dimensions", 2)
    if dims not in (2, 3) or isinstance(dims, bool):
        raise SpecError(f"figure: 'dimensions' must be 2 or 3, got {dims!r}")
    if dims == 3:
        return compile_spec3d(spec, sense_ranges)
    name, raw_bodies, bodies = _name_and_bodies(spec, _body)
    check_ground(spec)
    root = spec.get("root", {})
    if not isinstance(root, dict):
        raise SpecError("root: must be a table")
    rtype = root.get("type", "planar")
    if rtype not in ("planar", "fixed"):
        raise SpecError(f"root: unknown type {rtype!r} (planar, fixed)")
    root_body = root.get("body", raw_bodies[0].get("name"))
    joints = [_joint(j, bodies, i) for i, j in enumerate(spec.get("joints", []))]
    if len({j["name"] for j in joints}) != len(joints):
        raise SpecError("joint names must be unique")
    ordered = _tree_order(list(bodies), joints, root_body)
    pos = _vec(root, "position", "root", 2, default=[0.0, 0.0])
    ang = _num(root, "angle", "root", default=0.0)

    links = []  # dicts: parent, jtype, xtree, body, joint
    body_link = {}
    if rtype == "planar":
        links.append(dict(name="root_x", parent=-1, jtype=SLIDE_X, xtree=(0, 0, 0), body=None, q0=pos[0]))
        links.append(dict(name="root_z", parent=0, jtype=SLIDE_Z, xtree=(0, 0, 0), body=None, q0=pos[1]))
        links.append(dict(name="root_pitch", parent=1, jtype=REVOLUTE, xtree=(0, 0, 0), body=root_body, q0=ang))
        body_link[root_body] = 2
    else:
        body_link[root_body] = -1
    c, s = math.cos(ang), math.sin(ang)
    for j in ordered:
        p = body_link[j["parent"]]
        off, a = j["offset"], j["angle"]
        if p == -1:  # hangs from a fixed root: fold the placement into xtree
            off = pos + np.array([c * off[0] - s * off[1], s * off[0] + c * off[1]])
            a = a + ang
        body_link[j["child"]] = len(links)
        links.append(dict(name=j["name"], parent=p, jtype=REVOLUTE, xtree=(a, off[0], off[1]),
                          body=j["child"], joint=j, q0=j["initial"]))
    nl = len(links)
    if nl == 0:
        raise SpecError(f"figure {name!r}: nothing moves (fixed root and no joints)")

    def body_arr(key, shape):
        out = np.zeros((nl,) + shape)
        for i, L in enumerate(links):
            if L["body"] is not None:
                out[i] = bodies[L["body"]][key]
        return out

    lo = np.full(nl, -np.inf)
    hi = np.full(nl, np.inf)
    damping = np.zeros(nl)
    act = [(i, L["joint"]) for i, L in enumerate(links) if "joint" in L and L["joint"]["actuated"]]
    for i, L in enumerate(links):
        if "joint" in L:
            lo[i], hi[i], damping[i] = L["joint"]["lo"], L["joint"]["hi"], L["joint"]["damping"]
    for i, j in act:
        if j["kp"] <= 0 or j["tau_max"] <= 0:
            raise SpecError(f"joint {j['name']!r}: an actuated joint needs kp > 0 and torque_limit > 0")
    contacts = _points(spec.get("contacts", []), "contact", bodies)
    sites = _points(spec.get("sites", []), "site", bodies)
    seg_bodies = list(bodies)
    total_mass = sum(b["mass"] for b in bodies.values() if body_link[b["name"]] >= 0)
    actuator_names = [j["name"] for _, j in act]
    contact_names = [c_[0] for c_ in contacts]
    sense_names, sense_lo, sense_hi, sense_at = sense_layout(
        "planar", actuator_names, contact_names, np.array([j["lo"] for _, j in act]),
        np.array([j["hi"] for _, j in act]), total_mass, sense_ranges or {})
    model = Model(
        parent=np.array([L["parent"] for L in links], dtype=np.int64),
        jtype=np.array([L["jtype"] for L in links], dtype=np.int64),
        xtree=np.array([L["xtree"] for L in links], dtype=np.float64),
        mass=body_arr("mass", ()), com=body_arr("com", (2,)), icom=body_arr("inertia", ()),
        lo=lo, hi=hi, damping=damping,
        act_dof=np.array([i for i, _ in act], dtype=np.int64),
        **servo_arrays(act),
        cp_link=np.array([body_link[c_[1]] for c_ in contacts], dtype=np.int64),
        cp_pos=np.array([c_[2] for c_ in contacts], dtype=np.float64).reshape(-1, 2),
        seg_link=np.array([body_link[b] for b in seg_bodies], dtype=np.int64),
        seg_a=np.array([bodies[b]["seg"][0] for b in seg_bodies]),
        seg_b=np.array([bodies[b]["seg"][1] for b in seg_bodies]),
        seg_r=np.array([bodies[b]["radius"] for b in seg_bodies]),
        fixed_pose=np.array([ang, pos[0], pos[1]]),
        base_link=body_link[root_body],
        **limit_gains(spec),
        sense_lo=sense_lo, sense_hi=sense_hi, sense_at=sense_at,
    )
    return figure_of(spec, model, 2, links=links, sites=sites, body_link=body_link,
                     name=name, root=rtype, actuator_names=actuator_names,
                     contact_names=contact_names, sense_names=sense_names, body_names=seg_bodies,
                     q_default=np.array([L["q0"] for L in links], dtype=np.float64),
                     total_mass=total_mass)
