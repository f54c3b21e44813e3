"""The lamp does the limbo under poles of several heights (Gritz & Hahn).

One run per height; prints a table of who got under which pole.
Same as: gpmotion run lamp_limbo --param pole_height=0.38,0.42,0.46

    python examples/limbo_series.py
"""
from gpmotion import RunConfig, read_json, run

for height in (0.38, 0.42, 0.46):
    out = f"runs/example-limbo/pole_height={height}"
    cfg = RunConfig(task="lamp_limbo", seed=0, params={"pole_height": height},
                    search={"population": 300, "generations": 40})
    run(cfg, out, force=True, quiet=True)
    best = read_json(f"{out}/best.json", kind="best")
    print(f"pole at {height:.2f} m: {'solved' if best['success'] else 'not solved'}  "
          + "; ".join(best["facts"]))
