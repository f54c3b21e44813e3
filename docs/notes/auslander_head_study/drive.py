"""Run configurations that benchmarks/auslander_2d.py does not keep: a JSON object
{name: [task, family, task params, family options, expected gaits, label]} is
added to its CONFIGS, then its main() runs with the remaining arguments.  One
process per call (the pool's spawned workers would not see the added configs)."""
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[3] / "benchmarks"))
import auslander_2d as A  # noqa: E402

if __name__ == "__main__":
    extra, argv = json.loads(sys.argv[1]), sys.argv[2:]
    if "--workers" in argv and argv[argv.index("--workers") + 1] != "1":
        print("drive.py: use --workers 1 (run several drive.py processes instead)", file=sys.stderr)
        sys.exit(2)
    for k, (task, fam, params, options, gaits, label) in extra.items():
        A.CONFIGS[k] = (task, fam, params, options, tuple(gaits), label)
    A.main(argv)
