"""Reliability figures, repeatable: kills at random instants and a bad-input catalogue.

1. Kills: for GP (lamp_hop) and the serial search (bsr-time on starman_travel),
   one uninterrupted reference run, then N runs SIGKILLed at a random instant
   (uniform over the reference's duration) and resumed (`gpmotion resume`).
   Counted: resumed runs whose best.json (genome, cost), final checkpoint
   search state and log.csv (less its timing columns) equal the reference's.
2. Bad inputs: hand-edited config.json / checkpoint.json / log.csv and bad
   command-line values, each run through `gpmotion` in-process.  Counted:
   clean one-line errors (exit 2), expected successes, tracebacks, others.

    python benchmarks/reliability.py [--kills 10] [--only kills|inputs] [-v]
"""
from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import traceback
from pathlib import Path

import numpy as np

KINDS = {
    "gp": ["run", "lamp_hop", "--param", "seconds=0.3", "--population", "16",
           "--generations", "12", "--quiet", "--no-artifacts"],
    "serial": ["run", "starman_travel", "--controller", "bsr-time", "--param", "seconds=0.3",
               "--working", "4", "--generations", "600", "--quiet", "--no-artifacts"],
}


def gpm(argv, env=None, **kw):
    return subprocess.Popen([sys.executable, "-m", "gpmotion.cli", *map(str, argv)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            env={**os.environ, **(env or {})}, **kw)


def fingerprint(run: Path):
    """What must not depend on a kill: best controller, final search state, log."""
    best = json.loads((run / "best.json").read_text())
    ck = json.loads((run / "checkpoint.json").read_text())
    rows = [r.split(",") for r in (run / "log.csv").read_text().splitlines()]
    keep = [i for i, n in enumerate(rows[0]) if n not in ("evals_per_s", "elapsed_s")]
    return (json.dumps(best["genome"], sort_keys=True), best["cost"],
            json.dumps(ck["search"], sort_keys=True), [[r[i] for i in keep] for r in rows])


def kills(kind: str, n: int, root: Path, rng, every: str, verbose: bool) -> dict:
    argv = KINDS[kind]
    ref = root / f"{kind}-ref"
    t0 = time.perf_counter()
    p = gpm([*argv, "--out", ref])
    if p.wait() != 0:
        raise SystemExit(f"reference {kind} run failed: {p.stderr.read()}")
    duration = time.perf_counter() - t0
    want = fingerprint(ref)
    same = before_end = before_config = 0
    for i in range(n):
        out = root / f"{kind}-{i}"
        delay = float(rng.uniform(0.0, duration))
        p = gpm([*argv, "--out", out], env={"GPMOTION_CHECKPOINT_EVERY": every})
        time.sleep(delay)
        p.send_signal(signal.SIGKILL)
        p.wait()
        killed_early = not (out / "best.json").exists()
        before_end += killed_early
        if (out / "config.json").exists():
            r = gpm(["resume", out, "--quiet"])
            err = r.communicate()[1]
            ok = r.returncode == 0 and fingerprint(out) == want
        else:                               # killed before it wrote anything: start again
            before_config += 1
            r = gpm([*argv, "--out", out, "--force"])
            err = r.communicate()[1]
            ok = r.returncode == 0 and fingerprint(out) == want
        same += ok
        if verbose:
            print(f"  {kind} kill {i}: at {delay:5.2f} s of {duration:.1f} s, "
                  f"{'mid-run' if killed_early else 'after the end'}: "
                  f"{'identical' if ok else 'DIFFERENT ' + err.strip()[-200:]}")
    return {"kind": kind, "kills": n, "identical": same, "killed_mid_run": before_end,
            "before_config": before_config, "reference_s": round(duration, 1)}


# ------------------------------------------------------------------ bad inputs

def _json_edit(name, fn):
    def edit(run: Path):
        p = run / name
        doc = json.loads(p.read_text())
        fn(doc)
        p.write_text(json.dumps(doc))
    return edit


def _text_edit(name, fn):
    def edit(run: Path):
        p = run / name
        p.write_text(fn(p.read_text()))
    return edit


def _symlink(name):
    def edit(run: Path):
        target = run.parent / f"outside-{name}"
        os.replace(run / name, target)
        os.symlink(target, run / name)
    return edit


def _set(path, value):
    def fn(doc):
        *head, last = path
        for k in head:
            doc = doc[k]
        doc[last] = value
    return fn


def _drop(path):
    def fn(doc):
        *head, last = path
        for k in head:
            doc = doc[k]
        del doc[last]
    return fn


CONFIG_CASES = [
    ("config: no run section", _drop(["run"])),
    ("config: run is a list", _set(["run"], [1, 2])),
    ("config: run.params is a list", _set(["run", "params"], ["seconds", 0.3])),
    ("config: run.params value is an object", _set(["run", "params", "seconds"], {"x": 1})),
    ("config: run.params unknown parameter", _set(["run", "params", "bogus"], 1)),
    ("config: run.params seconds 1e-9", _set(["run", "params", "seconds"], 1e-9)),
    ("config: run.params w_max... 1e308", _set(["run", "params", "distance"], 1e308)),
    ("config: run.search is a list", _set(["run", "search"], [1])),
    ("config: run.search unknown key", _set(["run", "search", "bogus"], 1)),
    ("config: run.search population 'many'", _set(["run", "search", "population"], "many")),
    ("config: run.search population -1", _set(["run", "search", "population"], -1)),
    ("config: run.search generations 0", _set(["run", "search", "generations"], 0)),
    ("config: run.seed a string", _set(["run", "seed"], "0")),
    ("config: run.seed -1", _set(["run", "seed"], -1)),
    ("config: run.task unknown", _set(["run", "task"], "nope")),
    ("config: run.family unknown", _set(["run", "family"], "nn")),
    ("config: run.actuation 'warp'", _set(["run", "actuation"], "warp")),
    ("config: run.family_options rules 1e7", _set(["run", "family_options", "rules"], 10**7)),
    ("config: run unknown key", _set(["run", "zzz"], 1)),
    ("config: run_id removed", _drop(["run_id"])),
    ("config: run_id changed", _set(["run_id"], "0123456789abcdef")),
    ("config: extended_generations -4", _set(["extended_generations"], -4)),
]
CHECKPOINT_CASES = [
    ("checkpoint: evaluations 1e400", None),
    ("checkpoint: evaluations -5", _set(["evaluations"], -5)),
    ("checkpoint: evaluations '7'", _set(["evaluations"], "7")),
    ("checkpoint: evaluations missing", _drop(["evaluations"])),
    ("checkpoint: log_rows 10^9", _set(["log_rows"], 10**9)),
    ("checkpoint: run_id of another run", _set(["run_id"], "0123456789abcdef")),
    ("checkpoint: config_digest other", _set(["config_digest"], "0" * 64)),
    ("checkpoint: search population changed", _set(["search", "config", "population"], 12)),
    ("checkpoint: search seed changed", _set(["search", "config", "seed"], 5)),
    ("checkpoint: search is a list", _set(["search"], [])),
    ("checkpoint: search missing", _drop(["search"])),
    ("checkpoint: search.generation -1", _set(["search", "generation"], -1)),
    ("checkpoint: search.population truncated", _set(["search", "population"], [])),
    ("checkpoint: search.random garbage", _set(["search", "random"], {"version": 3})),
    ("checkpoint: elapsed_s -1", _set(["elapsed_s"], -1)),
]
FILE_CASES = [
    ("config: truncated", _text_edit("config.json", lambda s: s[: len(s) // 2]), "error"),
    ("config: not JSON", _text_edit("config.json", lambda s: "hello"), "error"),
    ("config: symlink", _symlink("config.json"), "error"),
    ("checkpoint: truncated", _text_edit("checkpoint.json", lambda s: s[: len(s) // 2]), "error"),
    ("checkpoint: empty", _text_edit("checkpoint.json", lambda s: ""), "error"),
    ("checkpoint: NaN literal", _text_edit("checkpoint.json",
                                           lambda s: s.replace('"elapsed_s": ', '"elapsed_s": NaN, "x": ')), "error"),
    ("checkpoint: symlink", _symlink("checkpoint.json"), "error"),
    ("log: deleted", lambda run: (run / "log.csv").unlink(), "error"),
    ("log: last row removed", _text_edit("log.csv", lambda s: "".join(s.splitlines(True)[:-1])), "error"),
    ("log: torn last line", _text_edit("log.csv", lambda s: s + "9,9,0.1"), "ok"),
    ("log: rows after the checkpoint", _text_edit("log.csv", lambda s: s + s.splitlines(True)[-1]), "ok"),
    ("log: header garbage", _text_edit("log.csv", lambda s: "x,y\n" + s.split("\n", 1)[1]), "error"),
    ("log: symlink", _symlink("log.csv"), "error"),
]
PARTIAL = ["run", "lamp_hop", "--param", "seconds=0.3", "--population", "8", "--generations", "3",
           "--quiet", "--no-artifacts"]
BSR = ["run", "starman_travel", "--controller", "bsr-time", "--param", "seconds=0.3",
       "--generations", "2", "--working", "2", "--quiet", "--no-artifacts"]
CLI_CASES = [
    (BSR + ["--rules", "10000000"], "error"), (BSR + ["--param", "w_max_height=1e308"], "error"),
    (BSR + ["--param", "w_max_height=-1e6"], "ok"),
    (["--param", "seconds=nan"], "error"), (["--param", "seconds=1e-9"], "error"),
    (["--param", "distance=1e308"], "error"), (["--param", "distance=abc"], "error"),
    (["--param", "bogus=1"], "error"), (["--param", "noequals"], "error"),
    (["--param", "distance=0.3,99"], "error"), (["--generations", "-3"], "error"),
    (["--population", "2"], "ok"), (["--population", "1"], "error"),
    (["--seed", "-1"], "error"),
    (["--islands", "0"], "error"), (["--p-crossover", "2"], "error"),
]


def _call(argv) -> tuple[str, str]:
    """('error' | 'ok' | 'traceback' | 'other', detail) of one in-process gpmotion call."""
    from gpmotion.cli import main
    err = io.StringIO()
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            rc = main([str(a) for a in argv])
    except BaseException as e:                     # noqa: BLE001 - that is the point
        return "traceback", "".join(traceback.format_exception_only(type(e), e)).strip()
    text = err.getvalue().strip()
    if rc == 0:
        return "ok", ""
    lines = [ln for ln in text.splitlines() if ln.strip()]
    last = lines[-1] if lines else ""
    if rc == 2 and last.startswith("gpmotion: error:") and "Traceback" not in text:
        return "error", last
    return "other", f"rc {rc}: {text[-200:]}"


def _partial_run(root: Path) -> Path:
    """A run stopped after 2 of 3 generations (checkpoint and log present)."""
    from gpmotion.cli import _run_configs, parser
    from gpmotion.run import run
    args = parser().parse_args([*PARTIAL, "--out", str(root / "partial")])
    cfg, out = next(_run_configs(args))
    run(cfg, out, quiet=True, artifacts=False, max_generations=2, checkpoint_every=0)
    return Path(out)


def inputs(root: Path, verbose: bool) -> dict:
    base = _partial_run(root)
    cases = [(n, _json_edit("config.json", f) if f else None, "error") for n, f in CONFIG_CASES]
    cases += [(n, _json_edit("checkpoint.json", f) if f else _text_edit(
        "checkpoint.json", lambda s: s.replace('"evaluations": ', '"evaluations": 1e400, "x": ')),
        "error") for n, f in CHECKPOINT_CASES]
    cases += FILE_CASES
    counts = {"error": 0, "ok": 0, "traceback": 0, "other": 0, "wrong": 0}
    for i, (name, edit, expect) in enumerate(cases):
        run = root / f"case{i}"
        shutil.copytree(base, run, symlinks=True)
        edit(run)
        got, detail = _call(["resume", run, "--quiet"])
        _count(counts, name, expect, got, detail, verbose)
    for i, (extra, expect) in enumerate(CLI_CASES):
        out = root / f"cli{i}"
        argv = extra if extra[0] == "run" else [*PARTIAL, *extra]
        got, detail = _call([*argv, "--out", out])
        if got == "error" and out.exists():
            got, detail = "other", "wrote the run directory before refusing: " + detail
        _count(counts, "cli: " + " ".join(extra[-2:]), expect, got, detail, verbose)
    counts["cases"] = len(cases) + len(CLI_CASES)
    return counts


def _count(counts, name, expect, got, detail, verbose):
    if got in ("traceback", "other"):
        counts[got] += 1
    elif got != expect:
        counts["wrong"] += 1
        detail = f"expected {expect}, got {got} {detail}"
    else:
        counts[got] += 1
    if verbose:
        flag = "  " if got == expect else "!!"
        print(f"  {flag} {name:<45} {got:<9} {detail[:110]}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--kills", type=int, default=10, help="kills per search kind (default 10)")
    ap.add_argument("--checkpoint-every", default="0.2",
                    help="seconds between checkpoints in the killed runs (default 0.2: many "
                         "kills land between a checkpoint and the next)")
    ap.add_argument("--only", choices=["kills", "inputs"])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("-v", "--verbose", action="store_true")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    out = {}
    with tempfile.TemporaryDirectory(prefix="gpmotion-reliability-") as tmp:
        root = Path(tmp)
        if args.only in (None, "kills"):
            out["kills"] = [kills(k, args.kills, root, rng, args.checkpoint_every, args.verbose)
                            for k in KINDS]
        if args.only in (None, "inputs"):
            (root / "inputs").mkdir()
            out["inputs"] = inputs(root / "inputs", args.verbose)
    if args.json:
        print(json.dumps(out))
        return
    for k in out.get("kills", []):
        print(f"kills ({k['kind']}): {k['identical']}/{k['kills']} resumed to the uninterrupted "
              f"result ({k['killed_mid_run']} killed before the end, {k['before_config']} of "
              f"them before config.json existed; reference {k['reference_s']} s)")
    if "inputs" in out:
        c = out["inputs"]
        print(f"bad inputs: {c['error']} clean one-line errors + {c['ok']} expected successes "
              f"of {c['cases']}; {c['traceback']} tracebacks, {c['other']} other failures, "
              f"{c['wrong']} wrong outcomes")


if __name__ == "__main__":
    main()
