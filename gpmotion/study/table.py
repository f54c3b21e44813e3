"""A study's table from its ledger: per configuration, the labels counted and
the success rate with its 95 % Wilson interval, over one seed set.

Rates are reported on the spec's ``report_seeds`` only (the seeds no setting
was chosen on); ``tune`` seeds give counts, never a rate.  With ``starts``
the result of a seed is its cheapest start (by cost).  ``judge`` re-judges
every row from the measures the ledger keeps (no search is re-run).
"""
from __future__ import annotations

import csv
import io
import json
import math

import numpy as np

from .judge import get_judge, rejudge

Z95 = 1.959963984540054


def wilson(k: int, n: int, z: float = Z95) -> tuple[float, float]:
    """The Wilson score interval of k successes in n trials."""
    if n == 0:
        return (0.0, 1.0)
    p = k / n
    den = 1 + z * z / n
    mid = (p + z * z / (2 * n)) / den
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / den
    return max(0.0, mid - half), min(1.0, mid + half)


def chosen(rows: list[dict], seeds: list[int]) -> dict:
    """{(config, seed): the cheapest start's row} over ``seeds``."""
    out = {}
    for r in sorted(rows, key=lambda r: (r["config"], r["seed"], r["start"])):
        if r["seed"] not in seeds:
            continue
        k = (r["config"], r["seed"])
        if k not in out or r["cost"] < out[k]["cost"]:
            out[k] = r
    return out


def summarize(spec, rows: list[dict], seed_set: str = "report", judge: str | None = None) -> dict:
    """Per configuration: counts per label, success and interval, cost quartiles."""
    seeds = spec.report_seeds if seed_set == "report" else spec.tune_seeds
    picked = chosen(rows, seeds)
    out = []
    for conf in spec.configurations.values():
        recs = [picked[(conf.name, s)] for s in seeds if (conf.name, s) in picked]
        jname = judge or conf.judge
        j = get_judge(jname)
        expect = conf.expect if all(e in j.labels for e in conf.expect) else []
        verdicts = [rejudge(r, jname, expect) if judge else (r["success"], r["label"])
                    for r in recs]
        counts = {lab: sum(v[1] == lab for v in verdicts) for lab in j.labels}
        tested = [v[0] for v in verdicts if v[0] is not None]
        k, n = sum(bool(t) for t in tested), len(tested)
        cost = np.array([r["cost"] for r in recs], float)
        item = {"configuration": conf.name, "label": conf.label, "judge": jname,
                "expect": expect, "runs": len(recs), "of_seeds": len(seeds),
                "seeds": [r["seed"] for r in recs], "counts": counts,
                "success": k if n else None, "tested": n,
                "evaluations": sorted({int(r["evaluations"]) for r in recs}),
                "cost_median": float(np.median(cost)) if recs else None,
                "cost_q25": float(np.percentile(cost, 25)) if recs else None,
                "cost_q75": float(np.percentile(cost, 75)) if recs else None,
                "wall_s_median": float(np.median([r["wall_s"] for r in recs])) if recs else None}
        if seed_set == "report" and n:
            item["interval95"] = list(wilson(k, n))
        out.append(item)
    return {"study": spec.name, "title": spec.title, "seeds": seed_set, "seed_list": seeds,
            "quick": spec.quick, "rows": out}


def _evals(e: list) -> str:
    return "—" if not e else f"{e[0]:,}" if len(e) == 1 else f"{e[0]:,}–{e[-1]:,}"


def markdown(summary: dict) -> str:
    rows = [r for r in summary["rows"] if r["runs"]]
    if not rows:
        return f"no {summary['seeds']}-seed rows yet in the ledger of {summary['study']}\n"
    labels = [lab for lab in dict.fromkeys(x for r in rows for x in r["counts"])
              if any(r["counts"].get(lab) for r in rows)]
    rate = "success (95 % interval)" if summary["seeds"] == "report" else "success (tune seeds: no rate)"
    head = ["configuration", "runs", "evaluations per run", *labels, rate, "cost median [q25, q75]"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        counts = [str(r["counts"][lab]) if lab in r["counts"] else "—" for lab in labels]
        lines.append("| " + " | ".join([r["label"], str(r["runs"]), _evals(r["evaluations"]),
                                        *counts, _success(r),
                                        f"{r['cost_median']:.3f} [{r['cost_q25']:.3f}, "
                                        f"{r['cost_q75']:.3f}]"]) + " |")
    seeds = summary["seed_list"]
    ran = sorted({s for r in rows for s in r["seeds"]})
    # the caption names the seeds the rows cover, not only the spec's list
    note = f"{summary['seeds']} seeds {_seed_range(ran)}"
    if ran != list(seeds):
        note += f" ({len(ran)} of the spec's {len(seeds)}: {_seed_range(list(seeds))})"
    note += "; --quick form" if summary["quick"] else ""
    return "\n".join(lines) + f"\n\n{note}\n"


def _success(r: dict) -> str:
    if r["success"] is None:
        return "—"
    what = f" ({' or '.join(r['expect'])})" if r["expect"] else ""
    if "interval95" in r:
        lo, hi = r["interval95"]
        return f"{r['success']} / {r['tested']}{what} [{100 * lo:.0f}–{100 * hi:.0f} %]"
    return f"{r['success']} / {r['tested']}{what}"


def _seed_range(seeds: list) -> str:
    if seeds and seeds == list(range(seeds[0], seeds[-1] + 1)):
        return f"{seeds[0]}–{seeds[-1]}" if len(seeds) > 1 else str(seeds[0])
    return ", ".join(map(str, seeds))


def to_csv(summary: dict) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    labels = list(dict.fromkeys(x for r in summary["rows"] for x in r["counts"]))
    w.writerow(["configuration", "label", "judge", "runs", "evaluations", *labels, "success",
                "tested", "interval95_lo", "interval95_hi", "cost_median", "cost_q25", "cost_q75",
                "wall_s_median"])
    for r in summary["rows"]:
        lo, hi = r.get("interval95", ("", ""))
        w.writerow([r["configuration"], r["label"], r["judge"], r["runs"],
                    " ".join(map(str, r["evaluations"])), *(r["counts"].get(x, "") for x in labels),
                    "" if r["success"] is None else r["success"], r["tested"], lo, hi,
                    *("" if r[k] is None else repr(r[k]) for k in
                      ("cost_median", "cost_q25", "cost_q75", "wall_s_median"))])
    return buf.getvalue()


def render(summary: dict, fmt: str) -> str:
    if fmt == "md":
        return markdown(summary)
    if fmt == "csv":
        return to_csv(summary)
    if fmt == "json":
        return json.dumps(summary, indent=1, sort_keys=True) + "\n"
    raise ValueError(f"--format: md, csv or json, got {fmt!r}")
