"""BVH export: the file parses (with our reader and, when installed, the
independent `bvh` package), its skeleton and motion have the right shape, and
forward kinematics computed from the BVH file alone (standard BVH semantics,
written out here) puts every body origin, capsule end point and End Site where
the simulator had it, to 1e-4 m, for planar and 3-D figures of every root type."""
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import gpmotion
from gpmotion import bvh as B
from gpmotion.figures import load_spec, planar_spec_to_3d
from gpmotion.model import FREE3D, Model3D
from gpmotion.sim import geometry, geometry3d

LAMP = Path(gpmotion.__file__).parent / "figures" / "lamp.toml"
TOL = 1e-4   # metres


# ---------------------------------------------------------------- figures

def rod3(name, length, direction, mass=1.0, radius=0.03):
    d = np.asarray(direction, float)
    return {"name": name, "mass": mass, "radius": radius,
            "segment": [[0, 0, 0], list(length * d / np.linalg.norm(d))]}


def gizmo():
    """A rotated free root; an euler joint with a rest rotation, a hinge about a
    non-coordinate axis, a passive slide joint carrying a further hinged body."""
    g = dict(kp=30.0, kd=0.5, torque_limit=40.0, limits=[-3.0, 3.0])
    return {"dimensions": 3, "name": "gizmo",
            "root": {"type": "free", "body": "core", "position": [0.3, -0.2, 1.5],
                     "rotation": [0.3, -0.2, 0.5]},
            "bodies": [dict(rod3("core", 0.4, (1, 0, 0), 2.0), segment=[[-0.2, 0, 0], [0.2, 0, 0]]),
                       rod3("arm", 0.5, (1, 0.2, 0)),
                       rod3("fin", 0.3, (0, 1, 1)),
                       rod3("slider", 0.2, (1, 0, 0)),
                       rod3("hand", 0.15, (0, 0, -1))],
            "joints": [dict(name="ja", parent="core", child="arm", offset=[0.2, 0, 0],
                            rotation=[0.2, 0.4, -0.1], type="euler", axes="zyx",
                            **{**g, "limits": [[-3.0, 3.0], [-1.4, 1.4], [-3.0, 3.0]]}),
                       dict(name="jb", parent="core", child="fin", offset=[-0.1, 0.05, 0.02],
                            rotation=[0.4, 0.1, -0.3], type="hinge", axis=[1, 1, 0], **g),
                       dict(name="js", parent="arm", child="slider", offset=[0.5, 0.1, 0],
                            type="slide", axis=[1, 0, 0], limits=[-0.3, 0.3], actuated=False,
                            initial=0.05),
                       dict(name="jh", parent="slider", child="hand", offset=[0.2, 0, 0],
                            type="hinge", axis=[0, 1, 0], **g)],
            "sites": [{"name": "hand_tip", "body": "hand", "position": [0, 0, -0.15]}]}


def chain_fixed():
    """A 3-D chain hanging from a rotated fixed mount (the root body has no link)."""
    g = dict(limits=[-10, 10], actuated=False)
    return {"dimensions": 3, "name": "chain_fixed",
            "root": {"type": "fixed", "body": "mount", "position": [0.1, 0.2, 2.0],
                     "rotation": [0.0, 0.0, 0.7]},
            "bodies": [rod3("mount", 0.2, (1, 0, 0)), rod3("l0", 0.5, (0, 0, -1)),
                       rod3("l1", 0.5, (0, 0, -1))],
            "joints": [dict(name="j0", parent="mount", child="l0", offset=[0.2, 0, 0],
                            type="euler", axes="yx", initial=[0.6, 0.3], **g),
                       dict(name="j1", parent="l0", child="l1", offset=[0, 0, -0.5],
                            axis=[1, 0, 1], initial=0.8, **g)]}


def lamp_fixed():
    spec = load_spec(LAMP)
    spec["root"] = dict(spec["root"], type="fixed", angle=0.4)
    return spec


def moving_targets(fig, seconds):
    """Keyframes that swing every actuator by up to ±0.8 rad inside its limits
    (an euler joint's middle axis must stay away from ±90°: gimbal lock)."""
    lo, hi = fig.actuator_limits().T
    n = fig.model.neutral
    amp = np.minimum(0.3 * (hi - lo), 0.8)
    return (np.array([0.0, seconds / 2, seconds]),
            np.stack([n, np.clip(n + amp, lo, hi), np.clip(n - 0.7 * amp, lo, hi)]))


def sim(spec_or_name, seconds=0.6, ground=True):
    fig = gpmotion.load_figure(spec_or_name)
    scene = gpmotion.make_scene(ground=ground)
    targets = moving_targets(fig, seconds) if fig.n_act else None
    return gpmotion.simulate(fig, seconds, targets=targets, scene=scene, record_every=20)


CASES = {
    "lamp": lambda: sim("lamp"),
    "lamp_fixed": lambda: sim(lamp_fixed()),
    "lamp3d_planar_root": lambda: sim(planar_spec_to_3d(load_spec(LAMP))),
    "lamp3d_free_root": lambda: sim(planar_spec_to_3d(load_spec(LAMP), root="free")),
    "gizmo": lambda: sim(gizmo(), ground=False),
    "chain_fixed": lambda: sim(chain_fixed(), 1.0, ground=False),
}


@pytest.fixture(scope="module", params=sorted(CASES))
def exported(request, tmp_path_factory):
    traj = CASES[request.param]()
    assert not traj.diverged[0]
    path = tmp_path_factory.mktemp("bvh") / f"{request.param}.bvh"
    n = B.write_bvh(path, traj)
    assert n == traj.q.shape[1]
    return traj, path


# ------------------------------------------------ BVH semantics, stated here

def rot(axis, deg):
    a = np.radians(deg)
    c, s, o, z = np.cos(a), np.sin(a), np.ones_like(a), np.zeros_like(a)
    m = {"X": [[o, z, z], [z, c, -s], [z, s, c]],
         "Y": [[c, z, s], [z, o, z], [-s, z, c]],
         "Z": [[c, -s, z], [s, c, z], [z, z, o]]}[axis]
    return np.moveaxis(np.array(m), (0, 1), (-2, -1))


def bvh_fk(joints, frames):
    """World (BVH coordinates) joint positions {name: [F, 3]}, rotations
    {name: [F, 3, 3]} and End Site positions {name: [F, 3]}.

    ``joints``: (name, parent index, offset, channels, end_site) in file order;
    a joint's local transform is T(offset + position channels) · R(ch1) · R(ch2) · R(ch3)."""
    F = frames.shape[0]
    pos, R, ends = {}, {}, {}
    col = 0
    names = [j[0] for j in joints]
    for name, parent, off, chans, end in joints:
        t = np.broadcast_to(np.asarray(off, float), (F, 3)).copy()
        r = np.broadcast_to(np.eye(3), (F, 3, 3)).copy()
        for ch in chans:
            v = frames[:, col]
            col += 1
            if ch.endswith("position"):
                t[:, "XYZ".index(ch[0])] += v
            else:
                r = r @ rot(ch[0], v)
        if parent < 0:
            pos[name], R[name] = t, r
        else:
            pn = names[parent]
            pos[name] = pos[pn] + np.einsum("fab,fb->fa", R[pn], t)
            R[name] = R[pn] @ r
        if end is not None:
            ends[name] = pos[name] + np.einsum("fab,b->fa", R[name], np.asarray(end, float))
    assert col == frames.shape[1]
    return pos, R, ends


def to_ours(p_bvh, scale=100.0):
    """BVH y-up centimetres (X, Y, Z) → gpmotion z-up metres (x, y, z) = (X, −Z, Y)/100."""
    p = np.asarray(p_bvh) / scale
    return np.stack([p[..., 0], -p[..., 2], p[..., 1]], -1)


def ours_to_bvh_rot(M):
    C = np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]])
    return C @ M @ C.T


def lift(p):
    """Planar (x, z) → (x, 0, z); 3-vectors unchanged."""
    p = np.asarray(p, float)
    if p.shape[-1] == 3:
        return p
    return np.stack([p[..., 0], np.zeros_like(p[..., 0]), p[..., 1]], -1)


def body_origins(traj):
    """World origin [F, n_bodies, 3] of every body's frame, from the simulator."""
    m = traj.figure.model
    poses = traj.poses()[0]
    links = np.asarray(m.seg_link)
    if traj.is3d:
        P = np.concatenate([poses[..., :3, 3], np.broadcast_to(m.fixed_pos, poses.shape[:1] + (1, 3))], 1)
        return P[:, links]
    P = np.concatenate([poses[..., 1:], np.broadcast_to(m.fixed_pose[1:], poses.shape[:1] + (1, 2))], 1)
    return lift(P[:, links])


def rest_geometry(fig):
    """Segments [n_seg, 2, 3] and body origins [n_bodies, 3] with every joint
    coordinate zero and the root at the origin, unrotated (the documented rest pose)."""
    m = fig.model
    q = np.zeros(fig.nq)
    if isinstance(m, Model3D):
        for i in range(len(m.parent)):
            if m.jtype[i] == FREE3D:
                q[m.qadr[i] + 3] = 1.0
        seg = geometry3d.segments_world(m, q)
        R, P = geometry3d.link_frames(m, q)
        P = np.concatenate([P, m.fixed_pos[None]])
        R = np.concatenate([R, m.fixed_rot[None]])
        origins = P[m.seg_link]
        Rroot, Proot = R[m.base_link], P[m.base_link]
    else:
        seg = lift(geometry.segments_world(m, q))
        poses = np.concatenate([geometry.link_poses(m, q), m.fixed_pose[None]])
        origins = lift(poses[m.seg_link][:, 1:])
        th = poses[m.base_link, 0]
        Rroot = np.array([[np.cos(th), 0, -np.sin(th)], [0, 1, 0], [np.sin(th), 0, np.cos(th)]])
        Proot = lift(poses[m.base_link, 1:])
    # express relative to the root body's frame (root at the origin, unrotated)
    return (seg - Proot) @ Rroot, (origins - Proot) @ Rroot


def check_against_simulation(traj, joints, frames, scale=100.0):
    fig = traj.figure
    pos, R, ends = bvh_fk(joints, frames)
    names = [j[0] for j in joints]
    assert sorted(names) == sorted(fig.body_names)
    origins = body_origins(traj)
    seg = traj.segments()[0]
    seg3 = lift(seg)
    rest_seg, rest_org = rest_geometry(fig)
    for k, name in enumerate(fig.body_names):
        # the body's origin
        np.testing.assert_allclose(to_ours(pos[name], scale), origins[:, k], atol=TOL, err_msg=name)
        # both capsule end points, carried by the joint's rotation from the rest pose
        for end in (0, 1):
            local_bvh = (rest_seg[k, end] - rest_org[k]) @ np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]]).T
            world = pos[name] + np.einsum("fab,b->fa", R[name], local_bvh * scale)
            np.testing.assert_allclose(to_ours(world, scale), seg3[:, k, end], atol=TOL,
                                       err_msg=f"{name} segment end {end}")
    # End Sites: at the tip of each leaf's segment
    assert ends, "no End Site"
    for name, p in ends.items():
        k = fig.body_names.index(name)
        d = [np.linalg.norm(seg3[:, k, i] - origins[:, k], axis=-1).max() for i in (0, 1)]
        np.testing.assert_allclose(to_ours(p, scale), seg3[:, k, int(np.argmax(d))], atol=TOL,
                                   err_msg=f"End Site of {name}")
    # the rest pose (all channels zero) is the spec's rest geometry (bodies on
    # slide joints excepted: their OFFSET is 0, the position channels say where they are)
    pos0, _, _ = bvh_fk(joints, np.zeros((1, frames.shape[1])))
    moved = {j[0] for j in joints if j[1] >= 0 and "Xposition" in j[3]}
    for k, name in enumerate(fig.body_names):
        if name in moved or any(names[j[1]] in moved for j in joints if j[0] == name and j[1] >= 0):
            continue
        np.testing.assert_allclose(to_ours(pos0[name][0], scale), rest_org[k], atol=1e-6)
    return ends


# ------------------------------------------------------------------ tests

def test_structure_and_motion_header(exported):
    traj, path = exported
    fig = traj.figure
    f = B.read_bvh(path)
    assert len(f.joints) == len(fig.body_names)
    assert {j.name for j in f.joints} == set(fig.body_names)
    root = f.joints[0]
    assert root.parent == -1 and root.channels == list(B.ROOT_CHANNELS)
    np.testing.assert_array_equal(root.offset, 0.0)
    slides = {fig.spec["joints"][i]["child"] for i in range(len(fig.spec.get("joints", [])))
              if fig.spec["joints"][i].get("type") == "slide"}
    for j in f.joints[1:]:
        assert j.parent >= 0
        if j.name in slides:
            assert j.channels == list(B.ROOT_CHANNELS)
            np.testing.assert_array_equal(j.offset, 0.0)   # positions are the full translation
        else:
            assert j.channels == list(B.ROT_CHANNELS)
    # End Sites exactly on the leaves
    parents = {j.parent for j in f.joints}
    for i, j in enumerate(f.joints):
        assert (j.end_site is not None) == (i not in parents)
    assert f.n_frames == traj.q.shape[1]
    assert f.frame_time == pytest.approx(traj.dt * traj.record_every, abs=1e-6)
    assert np.isfinite(f.frames).all()


def test_bvh_forward_kinematics_reproduce_the_simulation(exported):
    traj, path = exported
    f = B.read_bvh(path)
    joints = [(j.name, j.parent, j.offset, j.channels, j.end_site) for j in f.joints]
    check_against_simulation(traj, joints, f.frames)


def test_independent_parser_reads_the_same_file(exported):
    bvh = pytest.importorskip("bvh")
    traj, path = exported
    mocap = bvh.Bvh(path.read_text())
    names = mocap.get_joints_names()
    assert len(names) == len(traj.figure.body_names)
    assert mocap.nframes == traj.q.shape[1]
    assert mocap.frame_time == pytest.approx(traj.dt * traj.record_every, abs=1e-6)
    joints = []
    for node, name in zip(mocap.get_joints(), names):
        ends = list(node.filter("End"))
        end = [float(v) for v in ends[0]["OFFSET"]] if ends else None
        joints.append((name, mocap.joint_parent_index(name), mocap.joint_offset(name),
                       mocap.joint_channels(name), end))
    frames = np.array(mocap.frames, dtype=float)
    assert frames.shape == (mocap.nframes, sum(len(j[3]) for j in joints))
    check_against_simulation(traj, joints, frames)


def test_planar_figures_rotate_about_bvh_z_only(tmp_path):
    traj = sim("lamp")
    path = tmp_path / "lamp.bvh"
    B.write_bvh(path, traj)
    f = B.read_bvh(path)
    for j in f.joints:
        np.testing.assert_allclose(f.channel(j.name, "Xrotation"), 0.0, atol=1e-6)
        np.testing.assert_allclose(f.channel(j.name, "Yrotation"), 0.0, atol=1e-6)
    np.testing.assert_allclose(f.channel("base", "Zposition"), 0.0, atol=1e-6)  # −y = 0
    # the elbow angle is the upper arm's Zrotation (degrees)
    elbow = traj.q[0, :, traj.figure.link_names.index("elbow")]
    np.testing.assert_allclose(f.channel("upper_arm", "Zrotation"), np.degrees(elbow), atol=1e-4)
    # centimetres: the root's height
    np.testing.assert_allclose(f.channel("base", "Yposition"), 100 * traj.q[0, :, 1], atol=1e-4)


def test_scale_one_writes_metres(tmp_path):
    traj = sim(gizmo(), 0.3, ground=False)
    B.write_bvh(tmp_path / "m.bvh", traj, scale=1.0)
    f = B.read_bvh(tmp_path / "m.bvh")
    joints = [(j.name, j.parent, j.offset, j.channels, j.end_site) for j in f.joints]
    check_against_simulation(traj, joints, f.frames, scale=1.0)


def test_angles_stay_continuous_through_whole_turns(tmp_path):
    traj = sim("lamp", 0.6)
    F = traj.q.shape[1]
    q = traj.q.copy()
    q[0, :, 2] = np.linspace(0.0, 4 * np.pi, F)     # the base somersaults twice
    traj = replace(traj, q=q)
    B.write_bvh(tmp_path / "spin.bvh", traj)
    f = B.read_bvh(tmp_path / "spin.bvh")
    z = f.channel("base", "Zrotation")
    assert np.abs(np.diff(z)).max() < 90
    assert z[-1] - z[0] == pytest.approx(720.0, abs=1e-3)
    # a 3-D figure tumbling about a tilted axis: no channel jumps either
    traj3 = sim(gizmo(), 1.0, ground=False)
    F = traj3.q.shape[1]
    ang = np.linspace(0, 4 * np.pi, F)                 # 14° a frame
    ax = np.array([0.3, 0.5, 0.8]) / np.linalg.norm([0.3, 0.5, 0.8])
    q3 = traj3.q.copy()
    q3[0, :, 3:7] = np.column_stack([np.cos(ang / 2), np.sin(ang / 2)[:, None] * ax])
    traj3 = replace(traj3, q=q3)
    B.write_bvh(tmp_path / "tumble.bvh", traj3)
    f3 = B.read_bvh(tmp_path / "tumble.bvh")
    assert np.abs(np.diff(f3.frames[:, 3:6], axis=0)).max() < 45
    joints = [(j.name, j.parent, j.offset, j.channels, j.end_site) for j in f3.joints]
    check_against_simulation(traj3, joints, f3.frames)


def test_diverged_tail_is_cut_and_nothing_finite_is_an_error(tmp_path):
    traj = sim("lamp", 0.6)
    q = traj.q.copy()
    q[0, 5:, 3] = np.nan
    assert B.write_bvh(tmp_path / "cut.bvh", replace(traj, q=q)) == 5
    assert B.read_bvh(tmp_path / "cut.bvh").n_frames == 5
    q[0, :, 3] = np.nan
    with pytest.raises(ValueError, match="finite"):
        B.write_bvh(tmp_path / "none.bvh", replace(traj, q=q))
    assert not (tmp_path / "none.bvh").exists()
    with pytest.raises(ValueError, match="episode"):
        B.write_bvh(tmp_path / "e.bvh", traj, e=3)
    with pytest.raises(ValueError, match="scale"):
        B.write_bvh(tmp_path / "s.bvh", traj, scale=0)


def test_reader_rejects_malformed_files(tmp_path):
    traj = sim("lamp", 0.2)
    good = tmp_path / "good.bvh"
    B.write_bvh(good, traj)
    text = good.read_text()
    bad = tmp_path / "bad.bvh"
    bad.write_text(text.rsplit("\n", 2)[0] + "\n")           # a frame short
    with pytest.raises(ValueError, match="motion values"):
        B.read_bvh(bad)
    bad.write_text(text.replace("Zrotation", "Qrotation", 1))
    with pytest.raises(ValueError, match="channels"):
        B.read_bvh(bad)
    bad.write_text(text.split("MOTION")[0])
    with pytest.raises(ValueError, match="end of file"):
        B.read_bvh(bad)
