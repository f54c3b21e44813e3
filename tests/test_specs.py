"""Figure specs: shipped figures compile; bad specs give one clear line (CLI: exit 2)."""
import copy
import textwrap

import numpy as np
import pytest

import gpmotion
from gpmotion.cli import main
from gpmotion.figures import SpecError, compile_spec, figure_names, load_figure
from tests import figures_for_tests as F


@pytest.mark.parametrize("name", ["lamp", "starman", "beryl"])
def test_shipped_figures_compile_parents_first(name):
    fig = gpmotion.load_figure(name)
    m = fig.model
    assert all(p < i for i, p in enumerate(m.parent))       # parents-first order
    assert fig.total_mass > 0 and len(fig.sense_names) == len(m.sense_lo)
    assert np.all(m.sense_hi > m.sense_lo)
    assert np.all(m.lo[m.act_dof] <= m.neutral) and np.all(m.neutral <= m.hi[m.act_dof])
    assert name in figure_names()


def test_lamp_has_the_papers_parts():
    fig = gpmotion.load_figure("lamp")
    assert fig.actuator_names == ["shoulder", "elbow", "neck"]
    assert {"base_back", "base_front", "head_tip"} <= set(fig.contact_names)
    assert fig.total_mass == pytest.approx(1.65)


def _bad(mutate):
    spec = F.pendulum(n_links=2, actuated=True)
    mutate(spec)
    return spec


@pytest.mark.parametrize("mutate, needle", [
    (lambda s: s["joints"].append({"name": "loop", "parent": "l1", "child": "mount"}), "cycle"),
    (lambda s: s["joints"][1].update(parent="ghost"), "unknown parent body 'ghost'"),
    (lambda s: s["bodies"][1].update(mass=-1.0), "'mass' must be > 0"),
    (lambda s: s["joints"][0].update(type="ball"), "unknown joint type 'ball'"),
    (lambda s: s["joints"][0].update(limits=[1.0, -1.0]), "lo < hi"),
    (lambda s: s["joints"][0].update(kp=float("nan")), "finite"),
    (lambda s: s["joints"][0].update(axis=[1, 0, 0]), "axis"),
    (lambda s: s["bodies"].append(copy.deepcopy(s["bodies"][1])), "defined twice"),
    (lambda s: s["bodies"].append({"name": "orphan", "mass": 1.0, "segment": [[0, 0], [1, 0]]}),
     "orphan"),
    (lambda s: s["root"].update(type="hovering"), "unknown type 'hovering'"),
    (lambda s: s["joints"][0].update(torque_limit=0.0), "torque_limit"),
])
def test_bad_specs_name_the_problem(mutate, needle):
    with pytest.raises(SpecError, match=needle.replace("(", r"\(").replace(")", r"\)")):
        compile_spec(_bad(mutate))


def test_bad_toml_and_cycle_files_exit_2_with_one_line(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text("name = 'x'\n[[bodies]\nmass = ")
    assert main(["render", "--figure", str(bad), "-o", str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("gpmotion: error:") and "TOML" in err and "\n" not in err
    cyc = tmp_path / "cycle.toml"
    cyc.write_text("""name = "cyc"
[root]
type = "planar"
body = "a"
[[bodies]]
name = "a"
mass = 1.0
segment = [[0, 0], [1, 0]]
[[bodies]]
name = "b"
mass = 1.0
segment = [[0, 0], [1, 0]]
[[joints]]
name = "ab"
parent = "a"
child = "b"
actuated = false
[[joints]]
name = "ba"
parent = "b"
child = "a"
actuated = false
""")
    assert main(["render", "--figure", str(cyc), "-o", str(tmp_path / "y.png")]) == 2
    err = capsys.readouterr().err.strip()
    assert "tree" in err or "parent" in err
    assert not (tmp_path / "y.png").exists()


def test_a_scene_without_ground_lets_the_lamp_fall_freely():
    fig = gpmotion.load_figure("lamp")
    tr = gpmotion.simulate(fig, 0.5, scene=gpmotion.make_scene(ground=False))
    z0, n, dt = tr.com[0, 0, 1], 500, 1e-3
    # semi-implicit Euler's exact discrete free fall: z_n = z_0 − g·dt²·n(n+1)/2
    assert tr.com[0, -1, 1] == pytest.approx(z0 - 9.81 * dt ** 2 * n * (n + 1) / 2, abs=1e-9)
    assert tr.contact_force.max() == 0


def test_a_figure_variant_extends_a_shipped_one(tmp_path, monkeypatch):
    """`extends`: tables merge, named entries update by name or append."""
    (tmp_path / "tall_lamp.toml").write_text(textwrap.dedent('''
        extends = "lamp"
        name = "tall_lamp"
        [[bodies]]
        name = "lower_arm"
        mass = 0.5
        [[joints]]
        name = "elbow"
        kp = 123.0
        [[sites]]
        name = "antenna"
        body = "head"
        position = [0.1, 0.0]
    '''))
    base, fig = load_figure("lamp"), load_figure(str(tmp_path / "tall_lamp.toml"))
    assert fig.name == "tall_lamp" and fig.body_names == base.body_names
    assert fig.site_names == base.site_names + ["antenna"]
    k = fig.actuator_names.index("elbow")
    assert fig.model.kp[k] == 123.0 and base.model.kp[k] != 123.0
    others = [i for i in range(base.n_act) if i != k]
    assert np.array_equal(fig.model.kp[others], base.model.kp[others])
    assert fig.total_mass == pytest.approx(base.total_mass + 0.25)      # lower arm 0.25 -> 0.5 kg
    with pytest.raises(SpecError, match="unknown figure 'nope'"):
        load_figure({"extends": "nope"})
    from gpmotion import figures
    monkeypatch.setitem(figures._REGISTRY, "loop_a", {"extends": "loop_b"})
    monkeypatch.setitem(figures._REGISTRY, "loop_b", {"extends": "loop_a"})
    with pytest.raises(SpecError, match="loop"):
        load_figure("loop_a")


def test_a_figure_names_its_ground():
    fig = load_figure({"extends": "lamp", "ground": {"k_ground": 2e4, "mu": 0.5}})
    assert fig.ground == {"k_ground": 2e4, "mu": 0.5} and load_figure("lamp").ground == {}
    tr = gpmotion.simulate(fig, 0.01)
    assert tr.scene.k_ground == 2e4 and tr.scene.mu == 0.5
    for bad, needle in (({"k_ground": -1.0}, "k_ground"), ({"stiffness": 1.0}, "unknown key"),
                        ("soft", "table")):
        with pytest.raises(SpecError, match=needle):
            load_figure({"extends": "lamp", "ground": bad})


def test_a_huge_figure_name_is_one_line_error():
    import pytest

    from gpmotion.figures import load_figure
    from gpmotion.figures.spec import SpecError
    with pytest.raises(SpecError, match="at most"):
        load_figure({"extends": "lamp", "name": "x" * 1_000_000})
