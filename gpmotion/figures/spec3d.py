"""3-D figure specs (``dimensions = 3``) → validated, compiled :class:`Figure`.

Format (TOML or dict; every vector is [x, y, z], z up, SI units, radians)::

    dimensions = 3
    name = "..."
    [root]
    type = "free"            # "free" (6 dof, quaternion), "fixed" (welded) or
                             # "planar" (slide x, slide z, hinge about −y)
    body = "pelvis"          # default: the first body
    position = [0, 0, 1.0]
    rotation = [rx, ry, rz]  # optional rest orientation (see below)
    angle = 0.0              # planar root only: initial pitch (CCW about −y)

    [[bodies]]
    name = "thigh"; mass = 4.0
    segment = [[0, 0, 0], [0, 0, -0.4]]   # capsule axis in the body frame
    radius = 0.05
    com = [0, 0, -0.2]                     # default: segment midpoint
    inertia = [Ixx, Iyy, Izz]              # or a 3×3 matrix, about the com;
    shape = "rod"                          # else derived: rod | box | capsule

    [[joints]]
    name = "hip"; parent = "pelvis"; child = "thigh"
    offset = [0, 0.1, 0]                   # joint origin in the parent frame
    rotation = [0, 0, 0]                   # optional fixed rest rotation
    type = "euler"; axes = "zyx"           # or type = "hinge", axis = [0, -1, 0]
                                           # (or "slide" along axis)
    limits = [[-1, 1], [-0.5, 0.5], [-2, 0.3]]   # per axis ([lo, hi] = same for all)
    neutral = [0, 0, 0]; initial = ...; kp = 200.0; kd = [5, 5, 8]
    torque_limit = 150.0; damping = 0.0; actuated = true

    [[contacts]] / [[sites]]: name, body, position = [x, y, z]
    sense = true                           # sites only: add the senses
                                           # site_<name>_dx/_dy/_dz (position − goal)
    [limits] stiffness, damping            # the joint-limit spring

Rotations: ``rotation = [rx, ry, rz]`` in radians (``rotation_deg`` in
degrees) are intrinsic x-y-z Euler angles, ``R = Rx(rx) · Ry(ry) · Rz(rz)``;
R maps the child (joint) frame's coordinates into the parent's.
A body's frame is the frame of the joint that attaches it (after the joint's
rest rotation and motion); the root body's frame is its placement.

An ``euler`` joint of k = 1..3 axes (animators'/BVH order: ``axes = "zyx"``
rotates about z first, then the new y, then the new x, R = Rz·Ry·Rx) becomes
a chain of k hinge links, the first k−1 massless, named ``<joint>_<axis>``
(or ``<joint>_<k>`` for vector axes); each is a separate actuator.
The massless links make a lined-up chain singular, so the compiler refuses
parallel consecutive axes and a 3-axis chain whose middle axis may reach
gimbal lock (within 5° of ±90° for "zyx"): give the middle axis limits.
"""
from __future__ import annotations

import math

import numpy as np

from ..model import FREE3D, HINGE3D, SLIDE3D, Figure, Model3D
from ..sim.rotations import axis_angle, rot_to_quat  # noqa: F401 (rot_to_quat: re-exported)
from ..sim.senses import sense_layout
from .specparse import (PLANAR_AXIS, SpecError, _body, _name_and_bodies, _num, _tree_order, _vec, body_segment,
                        check_ground, figure_of, joint_where, limit_gains, parse_points,
                        servo_arrays)

_AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}


def euler_xyz(rx, ry, rz) -> np.ndarray:
    """R = Rx(rx) · Ry(ry) · Rz(rz) (intrinsic x-y-z)."""
    cx, sx, cy, sy, cz, sz = (math.cos(rx), math.sin(rx), math.cos(ry), math.sin(ry),
                              math.cos(rz), math.sin(rz))
    Rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    Ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    Rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return Rx @ Ry @ Rz


def _rotation(d, where):
    if "rotation" in d and "rotation_deg" in d:
        raise SpecError(f"{where}: give 'rotation' (radians) or 'rotation_deg', not both")
    if "rotation_deg" in d:
        return euler_xyz(*np.radians(_vec(d, "rotation_deg", where, 3)))
    return euler_xyz(*_vec(d, "rotation", where, 3, default=[0.0, 0.0, 0.0]))


def _unit(v, where, key):
    n = float(np.linalg.norm(v))
    if n < 1e-9:
        raise SpecError(f"{where}: '{key}' must not be the zero vector")
    return np.asarray(v, dtype=np.float64) / n


def _body3d(b, i):
    where, mass, a, bb, radius, com = body_segment(b, i, 3)
    if "inertia" in b:
        I = b["inertia"]
        if isinstance(I, list) and len(I) == 3 and all(isinstance(r, list) for r in I):
            rows = [_vec({"r": r}, "r", where + " inertia", 3) for r in I]
            I = np.array(rows)
        else:
            I = np.diag(_vec(b, "inertia", where, 3))
        if not np.allclose(I, I.T, atol=1e-12) or np.linalg.eigvalsh(I).min() <= 0:
            raise SpecError(f"{where}: 'inertia' must be symmetric positive definite")
    else:
        L = float(np.linalg.norm(bb - a))
        shape = b.get("shape", "rod")
        if shape == "rod":
            it, ia = mass * L ** 2 / 12.0, mass * radius ** 2 / 2.0
        elif shape == "box":
            it, ia = mass * (L ** 2 + 4 * radius ** 2) / 12.0, 2.0 * mass * radius ** 2 / 3.0
        elif shape == "capsule":
            it, ia = mass * (3 * radius ** 2 + L ** 2) / 12.0, mass * radius ** 2 / 2.0
        else:
            raise SpecError(f"{where}: unknown shape {shape!r} (rod, box, capsule)")
        it = max(it, mass * radius ** 2 / 2.0)  # never thinner than its radius
        if L > 1e-12:
            d = (bb - a) / L
            I = it * (np.eye(3) - np.outer(d, d)) + ia * np.outer(d, d)
        else:
            I = np.eye(3) * 0.4 * mass * radius ** 2
    return dict(name=b["name"], mass=mass, com=com, inertia=np.asarray(I, dtype=np.float64),
                seg=(a, bb), radius=radius)


def _per_axis(j, key, where, k, default, lo=None):
    """A number for every axis: scalar (broadcast) or a list of k numbers."""
    v = j.get(key, default)
    if isinstance(v, list):
        if len(v) != k:
            raise SpecError(f"{where}: '{key}' needs {k} entries (one per axis), got {v!r}")
        return [_num({key: x}, key, where, lo=lo) for x in v]
    return [_num({key: v}, key, where, lo=lo)] * k


def _joint3d(j, bodies, i):
    where = joint_where(j, bodies, i)
    jt = j.get("type", "hinge")
    if jt == "fixed":   # welded: the child rides on the parent's link (no dof)
        return dict(name=j["name"], parent=j["parent"], child=j["child"], dofs=[],
                    offset=_vec(j, "offset", where, 3, default=[0.0, 0.0, 0.0]), rot=_rotation(j, where))
    if jt in ("hinge", "slide"):
        axes = [_unit(_vec(j, "axis", where, 3), where, "axis")]
        names = [j["name"]]
        kinds = [HINGE3D if jt == "hinge" else SLIDE3D]
    elif jt == "euler":
        ax = j.get("axes")
        if isinstance(ax, str):
            if not 1 <= len(ax) <= 3 or any(c not in _AXES for c in ax.lower()):
                raise SpecError(f"{where}: 'axes' must be 1-3 letters of x, y, z (e.g. \"zyx\"), got {ax!r}")
            axes = [np.array(_AXES[c]) for c in ax.lower()]
            names = [f"{j['name']}_{c}" for c in ax.lower()]
        elif isinstance(ax, list) and 1 <= len(ax) <= 3:
            axes = [_unit(_vec({"axes": a}, "axes", where, 3), where, "axes") for a in ax]
            names = [f"{j['name']}_{k}" for k in range(len(ax))]
        else:
            raise SpecError(f"{where}: 'axes' must be a string like \"zyx\" or a list of 1-3 axis vectors")
        if len(set(names)) != len(names):
            raise SpecError(f"{where}: 'axes' repeats an axis name; give axis vectors instead")
        kinds = [HINGE3D] * len(axes)
    else:
        raise SpecError(f"{where}: unknown joint type {jt!r} (hinge, slide, euler, fixed)")
    k = len(axes)
    lim = j.get("limits", [-math.pi, math.pi])
    if isinstance(lim, list) and lim and all(isinstance(x, list) for x in lim):
        if len(lim) != k:
            raise SpecError(f"{where}: 'limits' needs {k} [lo, hi] pairs (one per axis), got {lim!r}")
        lims = [_vec({"limits": x}, "limits", where, 2) for x in lim]
    else:
        lims = [_vec(j, "limits", where, 2, default=[-math.pi, math.pi])] * k
    for lo_hi in lims:
        if not lo_hi[0] < lo_hi[1]:
            raise SpecError(f"{where}: limits must be [lo, hi] with lo < hi, got {list(lo_hi)}")
    if jt == "euler":
        _check_gimbal(axes, lims, where)
    neutral = _per_axis(j, "neutral", where, k, 0.0)
    for n_, lh in zip(neutral, lims):
        if not lh[0] <= n_ <= lh[1]:
            raise SpecError(f"{where}: neutral {n_} lies outside limits {list(lh)}")
    initial = _per_axis(j, "initial", where, k, neutral)
    actuated = j.get("actuated", True)
    if not isinstance(actuated, bool):
        raise SpecError(f"{where}: 'actuated' must be true or false")
    kp = _per_axis(j, "kp", where, k, 0.0, lo=0.0)
    kd = _per_axis(j, "kd", where, k, 0.0, lo=0.0)
    tmax = _per_axis(j, "torque_limit", where, k, 0.0, lo=0.0)
    damping = _per_axis(j, "damping", where, k, 0.0, lo=0.0)
    if actuated:
        for n_, a, t in zip(names, kp, tmax):
            if a <= 0 or t <= 0:
                raise SpecError(f"{where}: an actuated joint needs kp > 0 and torque_limit > 0 ({n_})")
    dofs = [dict(name=names[m], jtype=kinds[m], axis=axes[m], lo=lims[m][0], hi=lims[m][1],
                 neutral=neutral[m], initial=initial[m], actuated=actuated, kp=kp[m], kd=kd[m],
                 tau_max=tmax[m], damping=damping[m]) for m in range(k)]
    return dict(name=j["name"], parent=j["parent"], child=j["child"],
                offset=_vec(j, "offset", where, 3, default=[0.0, 0.0, 0.0]),
                rot=_rotation(j, where), dofs=dofs)


GIMBAL_MARGIN_DEG = 5.0


def _combine(m1, c1, I1, m2, c2, I2):
    """Mass, com and inertia about the com of two rigid bodies welded together."""
    if m1 == 0.0:
        return m2, c2, I2
    m = m1 + m2
    c = (m1 * c1 + m2 * c2) / m
    shift = lambda mm, d: mm * (d @ d * np.eye(3) - np.outer(d, d))  # noqa: E731 parallel axis
    return m, c, I1 + shift(m1, c1 - c) + I2 + shift(m2, c2 - c)


def _check_gimbal(axes, lims, where):
    """An Euler chain's intermediate links are massless, so the chain must
    never lose a rank: consecutive axes not parallel, and (3 axes) the first
    and third never lined up within the middle axis's limits (gimbal lock:
    ±90° for a Tait-Bryan "zyx", 0° for a proper "zxz"), else the articulated
    inertia is singular there and the simulation blows up."""
    near = math.cos(math.radians(GIMBAL_MARGIN_DEG))
    for m in range(len(axes) - 1):
        if abs(float(axes[m] @ axes[m + 1])) > near:
            raise SpecError(f"{where}: axes {m + 1} and {m + 2} are (nearly) parallel; an euler "
                            f"joint needs a new direction at every axis")
    if len(axes) == 3:
        angles = np.linspace(*lims[1], 721)
        lined_up = np.abs((axis_angle(axes[1], angles) @ axes[2]) @ axes[0]) > near
        if lined_up.any():
            th = angles[lined_up.argmax()]
            raise SpecError(
                f"{where}: gimbal lock: axes 1 and 3 line up when the middle axis is at "
                f"{math.degrees(th):.0f}°; keep its limits at least {GIMBAL_MARGIN_DEG:.0f}° "
                f"away (e.g. within ±{90 - GIMBAL_MARGIN_DEG:.0f}° for \"zyx\")")


def compile_spec3d(spec: dict, sense_ranges=None) -> Figure:
    """Validate a ``dimensions = 3`` spec and compile it into a Figure (Model3D)."""
    if not isinstance(spec, dict):
        raise SpecError("a figure spec must be a table/dict")
    name, raw_bodies, bodies = _name_and_bodies(spec, _body3d)
    check_ground(spec, planar=False)
    root = spec.get("root", {})
    if not isinstance(root, dict):
        raise SpecError("root: must be a table")
    rtype = root.get("type", "free")
    if rtype not in ("free", "fixed", "planar"):
        raise SpecError(f"root: unknown type {rtype!r} (free, fixed, planar)")
    root_body = root.get("body", raw_bodies[0].get("name"))
    raw_joints = spec.get("joints", [])
    if not isinstance(raw_joints, list):
        raise SpecError("joints must be a list of tables")
    joints = [_joint3d(j, bodies, i) for i, j in enumerate(raw_joints)]
    if len({j["name"] for j in joints}) != len(joints):
        raise SpecError("joint names must be unique")
    ordered = _tree_order(list(bodies), joints, root_body)
    pos = _vec(root, "position", "root", 3, default=[0.0, 0.0, 0.0])
    Rroot = _rotation(root, "root")
    eye = np.eye(3)

    links = []   # name, parent, jtype, axis, xrot, xpos, body, dof (dict or None), q0 (list)
    body_link = {}
    if rtype == "free":
        links.append(dict(name="root", parent=-1, jtype=FREE3D, axis=np.zeros(3), xrot=eye,
                          xpos=np.zeros(3), body=root_body, dof=None,
                          q0=list(pos) + list(rot_to_quat(Rroot))))
        body_link[root_body] = 0
    elif rtype == "planar":
        if "rotation" in root or "rotation_deg" in root:
            raise SpecError("root: a planar root takes 'angle' (pitch), not 'rotation'")
        ang = _num(root, "angle", "root", default=0.0)
        links.append(dict(name="root_x", parent=-1, jtype=SLIDE3D, axis=np.array(_AXES["x"]),
                          xrot=eye, xpos=np.array([0.0, pos[1], 0.0]), body=None, dof=None, q0=[pos[0]]))
        links.append(dict(name="root_z", parent=0, jtype=SLIDE3D, axis=np.array(_AXES["z"]),
                          xrot=eye, xpos=np.zeros(3), body=None, dof=None, q0=[pos[2]]))
        links.append(dict(name="root_pitch", parent=1, jtype=HINGE3D, axis=np.array(PLANAR_AXIS),
                          xrot=eye, xpos=np.zeros(3), body=root_body, dof=None, q0=[ang]))
        body_link[root_body] = 2
    else:
        body_link[root_body] = -1
    in_link = {}   # body -> (R, t): its frame in its link's frame (fixed joints)
    for j in ordered:
        p = body_link[j["parent"]]
        Rb, tb = in_link.get(j["parent"], (eye, np.zeros(3)))
        xrot, xpos = Rb @ j["rot"], tb + Rb @ j["offset"]
        if not j["dofs"]:
            in_link[j["child"]], body_link[j["child"]] = (xrot, xpos), p
            continue
        if p == -1:  # hangs from a fixed root: fold the placement into the joint frame
            xrot, xpos = Rroot @ xrot, pos + Rroot @ xpos
        nd = len(j["dofs"])
        for m, d in enumerate(j["dofs"]):
            last = m == nd - 1
            links.append(dict(name=d["name"], parent=p, jtype=d["jtype"], axis=d["axis"],
                              xrot=xrot if m == 0 else eye, xpos=xpos if m == 0 else np.zeros(3),
                              body=j["child"] if last else None, dof=d, q0=[d["initial"]]))
            p = len(links) - 1
        body_link[j["child"]] = p
    nl = len(links)
    if nl == 0:
        raise SpecError(f"figure {name!r}: nothing moves (fixed root and no joints)")
    free = rtype == "free"
    qadr = np.array([0] + [i + 6 for i in range(1, nl)] if free else list(range(nl)), dtype=np.int64)
    dadr = np.array([0] + [i + 5 for i in range(1, nl)] if free else list(range(nl)), dtype=np.int64)
    nq, nv = (nl + 6, nl + 5) if free else (nl, nl)

    mass = np.zeros(nl)
    com = np.zeros((nl, 3))
    icom = np.zeros((nl, 3, 3))
    for bname, b in bodies.items():       # welded bodies add up on their link
        i = body_link[bname]
        if i >= 0:
            Rb, tb = in_link.get(bname, (eye, np.zeros(3)))
            mass[i], com[i], icom[i] = _combine(mass[i], com[i], icom[i], b["mass"],
                                                tb + Rb @ b["com"], Rb @ b["inertia"] @ Rb.T)
    lo, hi, damping = np.full(nv, -np.inf), np.full(nv, np.inf), np.zeros(nv)
    act = []
    for i, L in enumerate(links):
        d = L["dof"]
        if d is not None:
            lo[dadr[i]], hi[dadr[i]], damping[dadr[i]] = d["lo"], d["hi"], d["damping"]
            if d["actuated"]:
                act.append((i, d))
    def at(body, x):           # a body-frame point in its link's frame
        Rb, tb = in_link.get(body, (eye, np.zeros(3)))
        return tb + Rb @ x

    contacts = [(n, b, at(b, x), s) for n, b, x, s in parse_points(spec.get("contacts", []), "contact", bodies, 3, True)]
    sites = [(n, b, at(b, x), s) for n, b, x, s in parse_points(spec.get("sites", []), "site", bodies, 3, True)]
    seg_bodies = list(bodies)
    total_mass = sum(b["mass"] for b in bodies.values() if body_link[b["name"]] >= 0)
    actuator_names = [d["name"] for _, d in act]
    contact_names = [c[0] for c in contacts]
    sensed = [s for s in sites if s[3]]
    sense_names, sense_lo, sense_hi, sense_at = sense_layout(
        "3d", actuator_names, contact_names, np.array([d["lo"] for _, d in act]),
        np.array([d["hi"] for _, d in act]), total_mass, sense_ranges or {},
        sites=[s[0] for s in sensed])
    model = Model3D(
        parent=np.array([L["parent"] for L in links], dtype=np.int64),
        jtype=np.array([L["jtype"] for L in links], dtype=np.int64),
        axis=np.array([L["axis"] for L in links], dtype=np.float64).reshape(nl, 3),
        xrot=np.ascontiguousarray(np.array([L["xrot"] for L in links], dtype=np.float64).reshape(nl, 3, 3)),
        xpos=np.array([L["xpos"] for L in links], dtype=np.float64).reshape(nl, 3),
        qadr=qadr, dadr=dadr, mass=mass, com=com, icom=icom, lo=lo, hi=hi, damping=damping,
        act_dof=np.array([dadr[i] for i, _ in act], dtype=np.int64),
        act_q=np.array([qadr[i] for i, _ in act], dtype=np.int64),
        **servo_arrays(act),
        cp_link=np.array([body_link[c[1]] for c in contacts], dtype=np.int64),
        cp_pos=np.array([c[2] for c in contacts], dtype=np.float64).reshape(-1, 3),
        ss_link=np.array([body_link[s[1]] for s in sensed], dtype=np.int64),
        ss_pos=np.array([s[2] for s in sensed], dtype=np.float64).reshape(-1, 3),
        seg_link=np.array([body_link[b] for b in seg_bodies], dtype=np.int64),
        seg_a=np.array([at(b, bodies[b]["seg"][0]) for b in seg_bodies]).reshape(-1, 3),
        seg_b=np.array([at(b, bodies[b]["seg"][1]) for b in seg_bodies]).reshape(-1, 3),
        seg_r=np.array([bodies[b]["radius"] for b in seg_bodies], dtype=np.float64),
        fixed_rot=np.ascontiguousarray(Rroot, dtype=np.float64), fixed_pos=pos.copy(),
        base_link=body_link[root_body],
        **limit_gains(spec),
        sense_lo=sense_lo, sense_hi=sense_hi, sense_at=sense_at, nq=nq, nv=nv)
    q_default = np.concatenate([np.asarray(L["q0"], dtype=np.float64) for L in links])
    return figure_of(spec, model, 3, links=links, sites=sites, body_link=body_link,
                     name=name, root=rtype, actuator_names=actuator_names,
                     contact_names=contact_names, sense_names=sense_names, body_names=seg_bodies,
                     q_default=q_default, total_mass=total_mass)


def planar_spec_to_3d(spec: dict, root: str | None = None) -> dict:
    """Rewrite a planar (x–z) spec as a ``dimensions = 3`` spec of the same figure.

    Every hinge turns about (0, −1, 0) (the planar CCW convention), planar
    offsets/points (x, z) become (x, 0, z), a joint's rest ``angle`` a becomes
    ``rotation = [0, −a, 0]``, and each body gets an explicit inertia whose
    moment about y is the planar one (moments about the in-plane axes: the
    planar moment across the segment, m r²/2 along it).  ``root``: keep the
    spec's root type (default; "planar" stays a planar root) or "free"/"fixed".
    """
    if spec.get("dimensions", 2) == 3:
        raise SpecError("planar_spec_to_3d: the spec is already 3-D")

    def p3(v):
        return [float(v[0]), 0.0, float(v[1])]

    out = {k: v for k, v in spec.items() if k not in ("bodies", "joints", "contacts", "sites", "root")}
    out["dimensions"] = 3
    bodies = []
    for i, b in enumerate(spec.get("bodies", [])):
        bd = _body(b, i)
        a, bb = bd["seg"]
        d = np.array([bb[0] - a[0], 0.0, bb[1] - a[1]])
        n = np.linalg.norm(d)
        d = d / n if n > 0 else np.array([1.0, 0.0, 0.0])
        perp = np.array([-d[2], 0.0, d[0]])
        ey = np.array([0.0, 1.0, 0.0])
        ia = bd["mass"] * bd["radius"] ** 2 / 2.0
        I = bd["inertia"] * (np.outer(ey, ey) + np.outer(perp, perp)) + ia * np.outer(d, d)
        bodies.append({"name": b["name"], "mass": bd["mass"], "segment": [p3(a), p3(bb)],
                       "radius": bd["radius"], "com": p3(bd["com"]), "inertia": I.tolist()})
    out["bodies"] = bodies
    joints = []
    for j in spec.get("joints", []):
        nj = {k: v for k, v in j.items() if k not in ("offset", "angle", "axis")}
        nj["type"] = "hinge"
        nj["axis"] = list(PLANAR_AXIS)
        nj["offset"] = p3(j.get("offset", [0.0, 0.0]))
        nj["rotation"] = [0.0, -float(j.get("angle", 0.0)), 0.0]
        joints.append(nj)
    out["joints"] = joints
    for kind in ("contacts", "sites"):
        out[kind] = [dict(p, position=p3(p["position"])) for p in spec.get(kind, [])]
    r = dict(spec.get("root", {}))
    rtype = root or r.get("type", "planar")
    pos = r.get("position", [0.0, 0.0])
    ang = float(r.get("angle", 0.0))
    nr = {"type": rtype, "position": p3(pos)}
    if "body" in r:
        nr["body"] = r["body"]
    if rtype == "planar":
        nr["angle"] = ang
    else:
        nr["rotation"] = [0.0, -ang, 0.0]
    out["root"] = nr
    return out
