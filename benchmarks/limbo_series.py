"""The limbo series as Gritz & Hahn show it: lamp_limbo success rates at
four pole heights, with and without the pole curriculum, in one table.

With the curriculum the pole starts at 0.60 m (above the standing lamp) and
comes down to its height over the first half of the run; without it
(``pole_start = pole_height``) the pole is at its height from generation 0.
Every run is `gpmotion run lamp_limbo --param pole_height=H` on the defaults
(or ``--preset``), one after another.  Results are appended to ``--out``
(JSON lines) as they finish, and runs already there are skipped, so a killed
series continues where it stopped.

    python benchmarks/limbo_series.py [--heights 0.46,0.42,0.38,0.34] [--seeds 5]
                                      [--out limbo_series.jsonl] [--preset P] [--table-only]
"""
import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from lamp_success import run_seed  # noqa: E402

CURRICULUM_START = 0.60          # lamp_limbo's default pole_start


def load(path: Path) -> list[dict]:
    if not path.exists():
        return []
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


def table(rows: list[dict], heights, seeds: int) -> str:
    def cell(h, cur):
        got = [r for r in rows if r["pole_height"] == h and r["curriculum"] == cur]
        if not got:
            return "not run"
        ok = sum(r["success"] for r in got)
        wall = max(r["wall_s"] for r in got)
        return f"{ok}/{len(got)}" + ("" if len(got) == seeds else f" (of {seeds} planned)") + \
            f", slowest {wall:.0f} s"
    lines = ["| pole height (m) | with curriculum (pole lowered from 0.60 m) | without (pole fixed) |",
             "|---|---|---|"]
    lines += [f"| {h:.2f} | {cell(h, True)} | {cell(h, False)} |" for h in heights]
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--heights", default="0.46,0.42,0.38,0.34")
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--preset", default=None)
    ap.add_argument("--out", default="limbo_series.jsonl")
    ap.add_argument("--table-only", action="store_true", help="print the table of --out and exit")
    args = ap.parse_args(argv)
    try:
        heights = [float(h) for h in args.heights.split(",")]
    except ValueError:
        print(f"limbo_series: --heights must be a comma list of numbers, got {args.heights!r}",
              file=sys.stderr)
        return 2
    out = Path(args.out)
    rows = load(out)
    if not args.table_only:
        for seed in range(args.seeds):            # seed-major: a cut-short series fills every cell
            for h in heights:
                for cur in (True, False):
                    if any(r["pole_height"] == h and r["curriculum"] == cur and r["seed"] == seed
                           and r["preset"] == (args.preset or "default") for r in rows):
                        continue
                    params = {"pole_height": h, "pole_start": CURRICULUM_START if cur else h}
                    r = run_seed("lamp_limbo", seed, params, preset=args.preset)
                    r.update(pole_height=h, curriculum=cur, preset=args.preset or "default")
                    rows.append(r)
                    with out.open("a") as f:
                        f.write(json.dumps(r) + "\n")
                    print(f"h={h} curriculum={cur} seed {seed}: "
                          f"{'solved' if r['success'] else 'NOT solved'} in {r['wall_s']:.0f}s; "
                          f"{'; '.join(r['facts'])}", file=sys.stderr, flush=True)
    rows = [r for r in rows if r["preset"] == (args.preset or "default")]
    print(table(rows, heights, args.seeds))
    return 0


if __name__ == "__main__":
    sys.exit(main())
