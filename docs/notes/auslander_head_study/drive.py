"""Run configurations that benchmarks/auslander_2d.py does not keep, given as
JSON text: {name: [task, family, task params, family options, expected gaits,
label]}.  A shim over its ``--study FILE.json`` (the JSON is written to a
temporary file and checked there), kept so the commands in these notes run as
written; new studies can call ``--study`` directly."""
import json
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[3] / "benchmarks"))
import auslander_2d as A  # noqa: E402

if __name__ == "__main__":
    extra, argv = json.loads(sys.argv[1]), sys.argv[2:]
    with tempfile.TemporaryDirectory() as d:
        study = Path(d) / "study.json"
        study.write_text(json.dumps(extra))
        A.main(["--study", str(study), *argv])
