import sys, json
sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parents[3] / "benchmarks"))
import auslander_2d as A
if __name__ == "__main__":
    extra = json.loads(sys.argv[1])   # {name: [task, family, params, options, gaits, label]}
    for k, (task, fam, params, options, gaits, label) in extra.items():
        A.CONFIGS[k] = (task, fam, params, options, tuple(gaits), label)
    A.main(sys.argv[2:])
