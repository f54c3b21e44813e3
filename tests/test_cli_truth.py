"""The command says what it does: no silently ignored option, help that explains
phased costs, names with suggestions, `show`, variants, plugin-only checks."""
import json
import subprocess
import sys

import pytest

from gpmotion.cli import _run_configs, main, parser
from gpmotion.cli_options import OPTIONS, Option, allow, collect, register_option
from gpmotion.families import family_names
from tests.cli_checks import one_line_error, refused_before_the_directory

TINY = ["--param", "seconds=0.3", "--population", "12", "--generations", "2", "--quiet",
        "--no-artifacts"]
SERIAL_TINY = ["--param", "seconds=0.3", "--generations", "3", "--quiet", "--no-artifacts"]


@pytest.mark.parametrize("argv, needles", [
    (["--controller", "bsr-sense", "--population", "10", "--p-crossover", "0.5"],
     ["--population does not apply to --controller bsr-sense", "--p-crossover", "applies to gp"]),
    (["--rules", "4"], ["--rules does not apply to --controller gp", "bsr-sense, bsr-time"]),
    (["--controller", "bsr-time", "--selection", "tournament"], ["--selection"]),
    (["--controller", "bsr-sense", "--t-per", "1.0"], ["--t-per", "applies to bsr-time"]),
    (["--working", "5"], ["--working does not apply to --controller gp"]),
    (["--controller", "bsr-time", "--primitives", "add,sub"], ["--primitives"]),
    (["--tau", "0.2"], ["--tau does not apply", "kinematic"]),
])
def test_an_option_that_does_not_apply_is_refused(argv, needles, tmp_path, capsys):
    out = tmp_path / "o"
    refused_before_the_directory(capsys, ["run", "lamp_hop", "--out", str(out), *argv, *SERIAL_TINY],
                                 out, *needles)


@pytest.mark.parametrize("argv, needle", [
    (["--primitives", "add,sinn"], "did you mean 'sin'"),
    (["--primitives", "add,add"], "twice"),
    (["--erc-range", "2,1"], "LO < HI"),
    (["--erc-range", "x"], "LO,HI"),
    (["--tau", "0", "--actuation", "kinematic"], "--tau"),
    (["--controller", "bsr-sens"], "did you mean 'bsr-sense'"),
])
def test_gp_function_set_erc_and_tau_are_validated(argv, needle, tmp_path, capsys):
    assert main(["run", "lamp_hop", "--out", str(tmp_path / "o"), *argv, *SERIAL_TINY]) == 2
    one_line_error(capsys, needle)


def test_every_applicable_option_reaches_the_run_config():
    args = parser().parse_args(["run", "lamp_hop", "--primitives", "add,sub,iflte",
                                "--erc-range=-2,2", "--tau", "0.3", "--actuation", "kinematic",
                                "--population", "20", "--generations", "3", "--p-creep", "0.1"])
    (cfg, _), = list(_run_configs(args))
    assert cfg.family_options == {"primitives": ["add", "sub", "iflte"], "erc_range": [-2.0, 2.0],
                                  "tau": 0.3}
    assert cfg.search == {"population": 20, "generations": 3, "p_creep": 0.1}
    args = parser().parse_args(["run", "starman_travel", "--controller", "bsr-time", "--rules",
                                "5", "--t-per", "1.5", "--working", "4", "--generations", "7"])
    (cfg, _), = list(_run_configs(args))
    assert cfg.family_options == {"rules": 5, "t_per": 1.5}
    assert cfg.search == {"n_working": 4, "n_generations": 7}


def test_gp_function_set_and_erc_range_change_the_primitive_set(tmp_path):
    out = tmp_path / "r"
    assert main(["run", "lamp_hop", "--out", str(out), "--primitives", "add,sub,mul",
                 "--erc-range=-3,3", *TINY]) == 0
    cfg = json.loads((out / "config.json").read_text())
    assert cfg["family_config"]["primitives"] == ["add", "sub", "mul"]
    assert cfg["family_config"]["erc_range"] == [-3.0, 3.0]
    best = json.loads((out / "best.json").read_text())
    used = {tok for tree in best["genome"]["trees"] for tok in tree if isinstance(tok, str)}
    assert not used & {"sin", "cos", "iflte", "div"}
    assert main(["replay", str(out)]) == 0


def test_the_option_table_is_the_parser_and_names_real_families():
    help_text = parser()._subparsers._group_actions[0].choices["run"].format_help()
    for o in OPTIONS:
        assert set(o.families()) <= set(family_names()), o.flag
        assert o.flag in help_text
        assert o.target in ("search", "family")


def test_a_new_family_declares_its_own_options():
    class Args:
        population = 50
        my_knob = 3
        actuation = None
    opt = register_option(Option("--my-knob", "family", {"nn": "knob"}, "a knob", "the nn knob",
                                 dict(type=int)))
    try:
        allow("--population", "nn", "pop")
        search, fam = collect(Args, "nn")
        assert search == {"pop": 50} and fam == {"knob": 3}
        with pytest.raises(ValueError, match="--my-knob does not apply to --controller gp"):
            collect(Args, "gp")
    finally:
        OPTIONS.remove(opt)
        next(o for o in OPTIONS if o.flag == "--population").keys.pop("nn")


def test_version_help_and_python_dash_m(capsys):
    with pytest.raises(SystemExit) as e:
        main(["--version"])
    assert e.value.code == 0 and "gpmotion 0." in capsys.readouterr().out
    assert main(["help", "run"]) == 0
    text = capsys.readouterr().out
    assert "--population" in text and "phase" in text and "best" in text
    assert main(["help", "rn"]) == 2
    one_line_error(capsys, "did you mean 'run'")
    r = subprocess.run([sys.executable, "-m", "gpmotion", "--version"], capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 0 and r.stdout.startswith("gpmotion ")


@pytest.mark.parametrize("argv, needle", [
    (["run", "lamp_hopp"], "did you mean 'lamp_hop'"),
    (["show", "herman_wav"], "did you mean 'herman_wave'"),
    (["render", "--figure", "starmen"], "did you mean 'starman'"),
])
def test_unknown_names_suggest_the_closest(argv, needle, capsys):
    assert main(argv) == 2
    one_line_error(capsys, needle)


def test_show_prints_parameters_terms_and_senses(capsys):
    assert main(["show", "lamp_limbo"]) == 0
    text = capsys.readouterr().out
    for needle in ("pole_height", "0.1..1", "height of the pole", "eases from 0.6",
                   "phases in from 20% to 50% of the run", "main goal", "head_hit",
                   "controlled joints", "shoulder, elbow, neck", "base_centre", "force_head_tip",
                   "lamp (2-D"):
        assert needle in text, needle
    assert main(["list", "tasks"]) == 0
    assert "gpmotion show TASK" in capsys.readouterr().out


def test_task_bounds_are_enforced(capsys):
    assert main(["run", "lamp_limbo", "--param", "pole_height=2"]) == 2
    one_line_error(capsys, "pole_height must be within 0.1..1")


PLUGIN = '''import math
from gpmotion import primitive


@primitive("hypot_t", arity=2)
def hypot_t(a, b):
    return math.sqrt(a * a + b * b)
'''


def test_check_only_plugins_checks_only_the_users(tmp_path, capsys):
    (tmp_path / "hyp.py").write_text(PLUGIN)
    assert main(["check", "--plugins", str(tmp_path), "--only-plugins"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert lines == ["ok    primitive hypot_t"]
    assert main(["check", "--only-plugins"]) == 2
    one_line_error(capsys, "--only-plugins needs --plugins")


VARIANT = '''extends = "lamp"
name = "stiff_lamp"
[[joints]]
name = "elbow"
kp = 40.0
'''


def test_run_on_a_figure_variant_and_replay_without_the_file(tmp_path, capsys):
    variant = tmp_path / "stiff_lamp.toml"
    variant.write_text(VARIANT)
    out = tmp_path / "r"
    assert main(["run", "lamp_hop", "--figure", str(variant), "--out", str(out), *TINY]) == 0
    cfg = json.loads((out / "config.json").read_text())
    assert cfg["task_config"]["figure"] == "stiff_lamp"
    elbow = next(j for j in cfg["run"]["params"]["figure"]["joints"] if j["name"] == "elbow")
    assert elbow["kp"] == 40.0
    variant.unlink()                                    # the run does not need the file
    capsys.readouterr()
    assert main(["replay", str(out), "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    best = json.loads((out / "best.json").read_text())
    assert rep["cost"] == best["final_cost"]


def test_a_variant_missing_what_the_task_uses_is_refused(tmp_path, capsys):
    variant = tmp_path / "v.toml"
    variant.write_text('extends = "lamp"\nname = "v"\n[[joints]]\nname = "elbo"\nkp = 40.0\n')
    assert main(["run", "lamp_hop", "--figure", str(variant), "--out", str(tmp_path / "o")]) == 2
    one_line_error(capsys, "no such joint 'elbo' in lamp (did you mean 'elbow'?)")
    variant.write_text('extends = "starman"\nname = "v"\n')
    assert main(["run", "lamp_hop", "--figure", str(variant), "--out", str(tmp_path / "o")]) == 2
    one_line_error(capsys, "figure v lacks", "actuated joint 'shoulder'", "site 'base_centre'")
    assert not (tmp_path / "o").exists()


def test_seeds_print_an_aggregate(tmp_path, capsys):
    assert main(["run", "lamp_hop", "--seeds", "2", "--out", str(tmp_path / "s"), *TINY]) == 0
    out = capsys.readouterr().out
    finals = [json.loads((tmp_path / "s" / f"seed{k}" / "best.json").read_text())["final_cost"]
              for k in (0, 1)]
    line = out.strip().splitlines()[-1]
    assert line.startswith("2 runs: final cost") and "solved" in line
    med = sorted(finals)[0] / 2 + sorted(finals)[1] / 2
    assert f"median {med:.4f}" in line


def test_compare_refuses_a_gp_option_without_gp(tmp_path, capsys):
    out = tmp_path / "c"
    refused_before_the_directory(capsys, ["compare", "lamp_hop", "--controllers", "bsr-sense",
                                          "--population", "50", "--out", str(out)],
                                 out, "--population does not apply")


def _readme_commands():
    import re
    import shlex
    from pathlib import Path
    text = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    for block in re.findall(r"```\n(.*?)```", text, flags=re.S):
        block = block.replace("\\\n", " ")            # a command continued with a backslash
        for line in block.splitlines():
            line = line.split(" #")[0].strip()
            if line.startswith("gpmotion ") and not line.startswith("gpmotion bench"):
                yield shlex.split(line)[1:]


def test_every_readme_command_parses_and_its_options_are_in_help():
    cmds = list(_readme_commands())
    assert len(cmds) >= 10
    ap = parser()
    subs = ap._subparsers._group_actions[0].choices
    for argv in cmds:
        ap.parse_args(argv)                                  # SystemExit on an unknown option
        help_text = subs[argv[0]].format_help()
        for tok in argv[1:]:
            if tok.startswith("--"):
                assert tok.split("=")[0] in help_text, (argv, tok)


def test_a_variant_with_another_root_is_refused(capsys):
    assert main(["run", "herman_touch_object", "--figure", "herman_standing"]) == 2
    one_line_error(capsys, "free root", "fixed root")


def test_render_refuses_seconds_for_a_controller(tmp_path, capsys):
    (tmp_path / "best.json").write_text("{}")
    assert main(["render", str(tmp_path), "--seconds", "5", "-o", str(tmp_path / "x.png")]) == 2
    one_line_error(capsys, "--seconds applies to --figure")


def test_resume_of_a_series_folder_names_its_runs(tmp_path, capsys):
    for k in (0, 1):
        (tmp_path / "s" / f"seed{k}").mkdir(parents=True)
        (tmp_path / "s" / f"seed{k}" / "config.json").write_text("{}")
    assert main(["resume", str(tmp_path / "s")]) == 2
    one_line_error(capsys, "series of 2 runs", f"gpmotion resume {tmp_path / 's' / 'seed1'}")


def test_family_options_from_a_file_are_validated():
    """A hand-edited best.json may not carry a reversed ERC range or a degenerate BSR tick."""
    import pytest

    from gpmotion.families import make_family
    from gpmotion.task import get_task
    task = get_task("lamp_hop")
    for bad in ([1.0, -1.0], [0.0, float("inf")], ["a", 1]):
        with pytest.raises(ValueError, match="erc_range"):
            make_family("gp", task, erc_range=bad)
    for bad in (0.0, -1.0, 1e-9, "x"):
        with pytest.raises(ValueError, match="bsr_dt"):
            make_family("bsr-time", task, bsr_dt=bad)
    make_family("gp", task, erc_range=[-2.0, 2.0])
    make_family("bsr-time", task, bsr_dt=0.05)


def test_a_text_parameter_takes_a_comma_list_as_one_value_a_number_runs_a_series():
    """``--param after=walk.json,turn.json`` (the README's walk → turn → walk)
    is one run from both files' end; ``--param distance=0.3,0.5`` a series."""
    args = parser().parse_args(["run", "rex_walk", "--controller", "bsr-time",
                                "--param", "after=walk.json,turn.json"])
    (cfg, _), = list(_run_configs(args))
    assert cfg.params["after"] == "walk.json,turn.json"
    args = parser().parse_args(["run", "lamp_hop", "--param", "distance=0.3,0.5"])
    assert [cfg.params["distance"] for cfg, _ in _run_configs(args)] == ["0.3", "0.5"]   # parsed later
