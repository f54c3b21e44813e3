"""The sense layout has one source (gpmotion.sim.senses); kernels write at the
offsets compiled from it into the Model, never at literal ones."""
import numpy as np
import pytest

from gpmotion.bench import sine_workload
from gpmotion.controllers import schedule
from gpmotion.figures import compile_spec, load_figure
from gpmotion.model import make_scene
from gpmotion.sim import senses as S
from gpmotion.sim import spatial3d
from gpmotion.sim.rollout import rollout


def test_slot_constants_pair_with_the_slot_names():
    for k, name in enumerate(S.SLOTS["planar"]):
        assert getattr(S, name.upper()) == k, name
    for k, name in enumerate(S.SLOTS["3d"]):
        assert getattr(spatial3d, "S_" + name.upper()) == k, name


@pytest.mark.parametrize("figure", ["lamp", "herman"])
def test_sense_at_is_compiled_from_the_layout(figure):
    fig = load_figure(figure)
    m, names = fig.model, fig.sense_names
    slots = S.SLOTS[fig.model.BACKEND]
    body = [n for n, _ in S.BODY[fig.model.BACKEND]]
    assert names[:len(body)] == body
    for k, slot in enumerate(slots):
        at = m.sense_at[k]
        if slot in body:
            assert names[at] == slot
        elif slot in S.BLOCKS:
            first = [i for i, n in enumerate(names) if n.startswith(slot + "_")]
            assert at == (first[0] if first else at)
        else:                                   # computed, not in this layout: scratch
            assert at == len(names)


def _senses_by_name(fig):
    """Senses of a short rollout with contacts, one frame per step: {name: [F]}."""
    offset, amplitude, omega, phase = sine_workload(fig, 1, seed=3)
    scene = make_scene(**fig.ground, goal=(0.3, 0.1, 0.2) if fig.dimensions == 3 else (0.3, 0.2))
    q0 = fig.q_default.copy()
    tr = rollout(fig, scene, schedule.sines(offset, amplitude, omega, phase), n_steps=60,
                 record_every=1, q0=q0, record_senses=True)
    return tr, {n: tr.senses[0, :, k] for k, n in enumerate(fig.sense_names)}


@pytest.mark.parametrize("figure, added", [
    ("lamp", (("com_x", (-2.0, 2.0)),)),
    ("herman", (("com_y", (-2.0, 2.0)), ("com_vx", (-3.0, 3.0)))),
])
def test_adding_a_body_sense_in_the_one_source_moves_every_write(figure, added, monkeypatch):
    """Put body senses first in the layout: every later sense moves, and every
    name still reads the same value it reads in the default layout — and the
    added ones read what they say (the com channel)."""
    base = load_figure(figure)
    tr0, want = _senses_by_name(base)
    backend = base.model.BACKEND
    monkeypatch.setitem(S.BODY, backend, added + S.BODY[backend])
    fig = compile_spec(base.spec)
    assert fig.sense_names[:len(added)] == [n for n, _ in added]
    assert len(fig.sense_names) == len(base.sense_names) + len(added)
    tr, got = _senses_by_name(fig)
    np.testing.assert_array_equal(tr.q, tr0.q)          # the physics does not read senses
    for name, values in want.items():
        np.testing.assert_array_equal(got[name], values, err_msg=name)
    com = {"com_x": 0, "com_y": 1, "com_vx": 3 if fig.dimensions == 3 else 2}
    for name, _ in added:
        np.testing.assert_array_equal(got[name], tr.com[0, :, com[name]], err_msg=name)


@pytest.mark.parametrize("figure", ["lamp", "herman"])
def test_senses_say_what_their_names_say(figure):
    """For a known state: angles, rates, forces, time, com and (3-D) sites by name."""
    fig = load_figure(figure)
    tr, s = _senses_by_name(fig)
    m = fig.model
    act_q = m.act_q if fig.dimensions == 3 else m.act_dof
    for a, joint in enumerate(fig.actuator_names):
        np.testing.assert_array_equal(s[f"angle_{joint}"], tr.q[0, :, act_q[a]])
        np.testing.assert_array_equal(s[f"rate_{joint}"], tr.qd[0, :, m.act_dof[a]])
    for k, c in enumerate(fig.contact_names):
        np.testing.assert_array_equal(s[f"force_{c}"], tr.contact_force[0, :, k])
    assert tr.contact_force.max() > 0                    # the contacts were exercised
    np.testing.assert_allclose(s["t"], tr.times)
    z = 2 if fig.dimensions == 3 else 1
    np.testing.assert_array_equal(s["com_z"], tr.com[0, :, z])
    if fig.dimensions == 3:
        goal = tr.scene.goal3
        for name in fig.site_names:
            if f"site_{name}_dx" in s:
                d = np.stack([s[f"site_{name}_{ax}"] for ax in ("dx", "dy", "dz")], -1)
                np.testing.assert_allclose(d, tr.site(name)[0] - goal, atol=1e-9)


def test_a_body_sense_no_kernel_computes_is_refused(monkeypatch):
    monkeypatch.setitem(S.BODY, "planar", S.BODY["planar"] + (("spin", (0.0, 1.0)),))
    with pytest.raises(ValueError, match="spin"):
        compile_spec(load_figure("lamp").spec)
