"""The report stays small however long the run: the film is thinned to its share
of the page (a lamp page under 2 MB, a Herman page under 5 MB), evenly over the
generations, the first and the last kept."""
import json
import re

import pytest

from gpmotion.report import write_report
from gpmotion.run import RunConfig, run


def _many_generations(tmp_path, task, n, **search):
    """A tiny run whose generations.jsonl is stretched to ``n`` records (its own
    controllers, renumbered): the film a long run leaves, without the search."""
    out = tmp_path / task
    run(RunConfig(task=task, family="gp", seed=1, search=search), out, quiet=True,
        artifacts=False, checkpoint_every=0)
    recs = [json.loads(line) for line in (out / "generations.jsonl").read_text().splitlines()]
    lines = [json.dumps(dict(recs[g % len(recs)], generation=g)) for g in range(n)]
    (out / "generations.jsonl").write_text("\n".join(lines) + "\n")
    return out


@pytest.mark.parametrize("task,n,limit,search", [
    ("lamp_hop", 400, 2_000_000, {"population": 8, "generations": 2}),
    ("herman_touch_nose", 300, 5_000_000, {"population": 6, "generations": 1}),
])
def test_a_long_runs_page_stays_small(tmp_path, task, n, limit, search):
    page = write_report(_many_generations(tmp_path, task, n, **search))
    size = page.stat().st_size
    assert size <= limit, f"{task}: {size:,} bytes"
    data = json.loads(re.search(r'id="gpm-data">(.*?)</script>', page.read_text(), re.S).group(1))
    film = data["panels"][0]["film"]
    gens = [e["generation"] for e in film["entries"]]
    assert film["of"] == n and 20 <= len(gens) < n           # thinned, still a film
    assert gens[0] == 0 and gens[-1] == n - 1 and gens == sorted(gens)
