"""The report page in a real browser: headless Chromium (Debian's ``chromium``,
which .ci/run installs) driven by Playwright.  The page loads without console
errors; the player advances; a scrubbed time shows the frame the Python
renderer draws at that time; the film switches controllers; the 3-D view turns
under a drag; a comparison shows one player per family; a composite marks its
phases.  The runs are tiny: these check the page, not the searches.

``python -m pytest tests/test_report_browser.py -m slow`` also writes the
screenshots in docs/images/report_*.png (larger runs, so they show something).
"""
import io
import json
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from gpmotion.render3d import motion_frames
from gpmotion.replay import load_controller, replay_genome
from gpmotion.report import write_report
from gpmotion.run import RunConfig, run
from gpmotion.study import study_dir

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
        "--disable-background-networking", "--disable-component-update", "--disable-sync",
        "--use-gl=swiftshader", "--enable-unsafe-swiftshader"]
# Chromium's own notes on a software GL (not the page's): swiftshader's stalls
BENIGN = ("GPU stall due to ReadPixels", "Automatic fallback to software WebGL")
DOCS_IMAGES = Path(__file__).resolve().parents[1] / "docs" / "images"


# ------------------------------------------------------------------ the browser
@pytest.fixture(scope="session")
def browser():
    if not Path(CHROMIUM).is_file():
        pytest.fail(f"{CHROMIUM} is missing: the report's browser tests need Debian's chromium "
                    "package (`apt-get install -y chromium`; .ci/run installs it)", pytrace=False)
    from playwright.sync_api import sync_playwright
    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        yield b
        b.close()


class Page:
    """One report opened from disk, with the console's errors collected."""

    def __init__(self, browser, path: Path, size=(1100, 900)):
        self.page = browser.new_page(viewport={"width": size[0], "height": size[1]})
        self.errors = []
        self.page.on("console", lambda m: m.type == "error" and self.errors.append(m.text))
        self.page.on("pageerror", lambda e: self.errors.append(str(e)))
        self.page.goto(path.resolve().as_uri())
        self.page.wait_for_function("window.gpmotion && window.gpmotion.ready")

    def js(self, expr, arg=None):
        return self.page.evaluate(expr, arg)

    def player(self, i, call, arg=None):
        return self.js(f"([i, a]) => gpmotion.players[i].{call}", [i, arg])

    def canvas(self, i=0):
        return self.page.locator(f"#panel{i} canvas").first

    def pixels(self, i=0) -> np.ndarray:
        self.player(i, "draw()")
        return np.asarray(Image.open(io.BytesIO(self.canvas(i).screenshot())).convert("RGB"), int)

    def close(self):
        errors = [e for e in self.errors if not any(b in e for b in BENIGN)]
        self.page.close()
        return errors


@pytest.fixture
def opened(browser):
    pages = []

    def open_(path, **kw):
        pages.append(Page(browser, path, **kw))
        return pages[-1]
    yield open_
    for p in pages:
        p.close()


# ------------------------------------------------------------------ the runs (tiny)
def _run(root, task, seed=1, **search):
    out = root / task
    run(RunConfig(task=task, family="gp", seed=seed, search=search), out, quiet=True,
        artifacts=False, checkpoint_every=0)
    write_report(out)
    return out


@pytest.fixture(scope="session")
def pages(tmp_path_factory):
    from gpmotion.cli.compose import main as compose
    from gpmotion.compare import compare
    from tests.test_composite import write_controller
    root = tmp_path_factory.mktemp("report")
    lamp = _run(root, "lamp_hop", population=12, generations=4)
    herman = _run(root, "herman_touch_nose", population=8, generations=2)
    cmp = root / "compare"
    compare("lamp_hop", ["gp", "bsr-time"], 1, 40, cmp, params={"seconds": 0.5},
            population=10, quiet=True)
    write_report(cmp)
    write_controller(root / "a.json")
    write_controller(root / "b.json", family="bsr-time", seed=1)
    (root / "two.motion").write_text("phase one = dcm_x * (dtime ~= 0.5)\nphase two = max_t(cm_z)\n"
                                     "total = (1 + one) * (1 + two)\n")
    comp = root / "composite"
    code = compose([str(root / "two.motion"), "--controllers", str(root / "a.json"),
                    str(root / "b.json"), "--arrays", "2", "--rounds", "1", "--mutations", "1",
                    "--out", str(comp), "--no-artifacts", "--quiet"])
    assert code == 0
    write_report(comp)
    shipped = write_report(study_dir("gp-vs-bsr"), root / "study.html")    # a study's ledger
    return {"lamp": lamp, "herman": herman, "compare": cmp, "composite": comp, "study": shipped}


def _python_frames(run_dir):
    task, family, actuation, genome, _ = load_controller(run_dir)
    traj = replay_genome(task, family, actuation, genome)[0]
    return motion_frames(traj, 0, task=task)


def _orange(px) -> np.ndarray:
    """The figure's colour (lit orange), not the background, ground, grid or markers."""
    r, g, b = px[..., 0], px[..., 1], px[..., 2]
    return (r - b > 70) & (r > g) & (g > b)


# ------------------------------------------------------------------ the tests
@pytest.mark.parametrize("kind", ["lamp", "herman", "compare", "composite", "study"])
def test_the_page_loads_without_console_errors(browser, pages, kind):
    p = Page(browser, pages[kind] if kind == "study" else pages[kind] / "report.html")
    n = p.js("gpmotion.players.length")
    shots = [p.pixels(i) for i in range(n)]
    errors = p.close()
    assert not errors, errors
    assert n >= 1
    for px in shots:                       # every player drew its figure
        assert _orange(px).sum() > 50


def test_the_player_advances(opened, pages):
    p = opened(pages["lamp"] / "report.html")
    p.player(0, "seek(0)")
    before = p.pixels()
    p.page.locator("#panel0 .controls button").first.click()         # ▶
    p.page.wait_for_function("gpmotion.players[0].state().t > 0.3")
    p.page.locator("#panel0 .controls button").first.click()         # pause
    s = p.player(0, "state()")
    assert not s["playing"] and s["frame"] > 0
    after = p.pixels()
    assert (np.abs(after - before).sum(axis=2) > 30).sum() > 50


@pytest.mark.parametrize("kind", ["lamp", "herman"])
def test_a_scrubbed_time_shows_the_python_renderers_frame(opened, pages, kind):
    m = _python_frames(pages[kind])
    times, segs = np.asarray(m["times"]), np.asarray(m["segments"])
    p = opened(pages[kind] / "report.html")
    for k in (int(0.37 * len(times)), int(0.81 * len(times))):
        t = times[k] + 0.25 * (times[k + 1] - times[k])        # the slider snaps to a frame
        p.js("t => { const s = document.querySelector('#panel0 input[aria-label=time]');"
             " s.value = String(t); s.dispatchEvent(new Event('input')); }", float(t))
        s = p.player(0, "state()")
        assert s["frame"] == k and s["time"] == pytest.approx(times[k], abs=1e-5)
        shown = np.asarray(p.player(0, "points()"))
        assert shown.shape == segs[k].shape
        # within a millimetre of the Python renderer's frame, and not a neighbour's
        err = np.abs(shown - segs[k]).max()
        assert err < 1e-3, err
        nearest = min(range(len(segs)), key=lambda j: np.abs(shown - segs[j]).max())
        assert np.abs(segs[nearest] - segs[k]).max() == 0 or nearest == k
        # and drawn there: each segment's midpoint on screen is the figure's colour
        px = p.pixels()
        box = p.canvas().bounding_box()
        on = [_orange(px[int(y - box["y"]), int(x - box["x"])])
              for x, y in p.player(0, "project()")
              if 0 <= x - box["x"] < px.shape[1] and 0 <= y - box["y"] < px.shape[0]]
        assert len(on) >= 0.8 * len(segs[k]) and np.mean(on) >= 0.8, on


def test_the_film_switches_controllers(opened, pages):
    recs = (pages["lamp"] / "generations.jsonl").read_text().splitlines()
    assert len(recs) >= 2, "the tiny run must change its best at least once"
    p = opened(pages["lamp"] / "report.html")
    film = p.js("gpmotion.data.panels[0].film.entries.map(e => e.generation)")
    assert film == [json.loads(r)["generation"] for r in recs]
    p.page.locator("#film0").check()
    s0 = p.player(0, "state()")
    assert s0["mode"] == "film" and s0["generation"] == film[0]
    hud = p.page.locator("#panel0 .hud").inner_text()
    assert f"generation {film[0]} (1/{len(film)})" in hud
    p.player(0, "seek(a)", 0.6)
    first = np.asarray(p.player(0, "points()"))
    p.page.get_by_role("button", name="gen ▶").first.click()
    s1 = p.player(0, "state()")
    assert s1["generation"] == film[1] and s1["film_index"] == 1 and s1["t"] == 0
    p.player(0, "seek(a)", 0.6)
    second = np.asarray(p.player(0, "points()"))
    assert np.abs(first - second).max() > 1e-3                   # another controller's motion
    assert f"generation {film[1]} (2/{len(film)})" in p.page.locator("#panel0 .hud").inner_text()


def _drag(p, dx):
    box = p.canvas().bounding_box()
    x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    p.page.mouse.move(x, y)
    p.page.mouse.down()
    for k in range(1, 11):
        p.page.mouse.move(x + dx * k / 10, y + 10 * k / 10)
    p.page.mouse.up()


def test_the_3d_view_turns_under_a_drag(opened, pages):
    p = opened(pages["herman"] / "report.html")
    p.player(0, "seek(0.5)")
    s0 = p.player(0, "state()")
    assert s0["dims"] == 3
    before = p.pixels()
    _drag(p, 160)
    s1 = p.player(0, "state()")
    c0, c1, target = np.asarray(s0["camera"]), np.asarray(s1["camera"]), p.js(
        "gpmotion.players[0].controls.target.toArray()")
    # turned about the target: the same distance, another direction
    assert np.linalg.norm(c0 - target) == pytest.approx(np.linalg.norm(c1 - target), rel=1e-3)
    assert np.linalg.norm(c1 - c0) > 0.05 * np.linalg.norm(c0 - target)
    assert s1["frame"] == s0["frame"]
    assert (np.abs(p.pixels() - before).sum(axis=2) > 30).sum() > 200


def test_a_planar_view_does_not_turn(opened, pages):
    p = opened(pages["lamp"] / "report.html")
    c0 = p.player(0, "state()")["camera"]
    _drag(p, 160)
    assert p.player(0, "state()")["camera"] == pytest.approx(c0)


def test_the_comparison_shows_one_player_per_family(opened, pages):
    p = opened(pages["compare"] / "report.html")
    runs = json.loads((pages["compare"] / "runs.json").read_text())["runs"]
    families = list(dict.fromkeys(r["family"] for r in runs))
    assert families == ["gp", "bsr-time"]
    assert p.js("gpmotion.players.length") == len(families)
    assert p.page.locator(".view canvas").count() == len(families)
    names = p.js("gpmotion.data.panels.map(q => q.family)")
    assert names == families
    # each family's best seed with its film (the comparison keeps the run folders)
    assert all(n >= 1 for n in p.js("gpmotion.players.map(q => q.film ? q.film.length : 0)"))
    rows = p.page.locator("main > table tr").count()
    assert rows == 1 + len(families)                              # the table: head + a row each
    for i in range(len(families)):
        assert _orange(p.pixels(i)).sum() > 50


def test_a_study_shows_one_player_per_configuration(opened, pages):
    from gpmotion.study import load_directory
    spec, _ = load_directory(study_dir("gp-vs-bsr"))
    p = opened(pages["study"])
    assert p.js("gpmotion.players.length") == len(spec.configurations) == 3
    assert p.page.locator("main > table tr").count() == 1 + len(spec.configurations)


def test_the_composite_marks_its_phases(opened, pages):
    p = opened(pages["composite"] / "report.html")
    comp = json.loads((pages["composite"] / "composite.json").read_text())
    names = [ph["name"] for ph in p.js("gpmotion.data.panels[0].motion.phases")]
    assert names == ["one", "two"] and len(comp["phases"]) == 2
    marks = p.page.locator("#panel0 .timeline span")
    assert marks.all_inner_texts() == names
    phases = p.js("gpmotion.data.panels[0].motion.phases")
    for ph in phases:
        p.player(0, "seek(a)", (ph["from"] + ph["to"]) / 2)
        assert f"phase: {ph['name']}" in p.page.locator("#panel0 .hud").inner_text()



def test_the_jupyter_player_plays_in_the_browser(opened, pages, tmp_path):
    """A Trajectory's _repr_html_ is an iframe whose srcdoc is a working page."""
    import html
    import re
    task, family, actuation, genome, _ = load_controller(pages["herman"])
    traj = replay_genome(task, family, actuation, genome)[0]
    frag = traj._repr_html_()
    doc = html.unescape(re.fullmatch(r'<iframe style="[^"]*" srcdoc="([^"]*)"></iframe>', frag).group(1))
    (tmp_path / "inline.html").write_text(doc, encoding="utf-8")
    p = opened(tmp_path / "inline.html", size=(800, 560))
    p.player(0, "seek(a)", 0.5)
    assert p.player(0, "state()")["dims"] == 3 and _orange(p.pixels()).sum() > 50
    assert not [e for e in p.errors if not any(b in e for b in BENIGN)]

# ------------------------------------------------------------------ the docs' screenshots
def _shot(browser, path: Path, png: Path, t_frac: float, film: bool = False, height=1000):
    p = Page(browser, path, size=(1200, height))
    try:
        n = p.js("gpmotion.players.length")
        for i in range(n):
            if film:
                k = p.js("gpmotion.players[0].film.length") // 2
                p.player(i, "setFilm(a)", k)
            end = p.js("i => { const d = gpmotion.players[i].d; return d.times[d.n - 1]; }", i)
            p.player(i, "seek(a)", t_frac * end)
            p.player(i, "draw()")
        p.page.screenshot(path=str(png))
    finally:
        errors = p.close()
    assert not errors, errors
    assert png.stat().st_size > 20_000


@pytest.mark.slow
def test_the_docs_screenshots(browser, tmp_path):
    """docs/images/report_{run2d,run3d,compare,composite}.png: the pages of a
    lamp run, a Herman run, a comparison and a composite, shot in Chromium."""
    from gpmotion.cli.compose import main as compose
    from gpmotion.compare import compare
    lamp = _run(tmp_path, "lamp_hop", seed=0, population=40, generations=10)
    herman = _run(tmp_path, "herman_touch_nose", seed=0, population=24, generations=6)
    cmp = tmp_path / "compare"
    compare("lamp_hop", ["gp", "bsr-time"], 2, 400, cmp, quiet=True)
    write_report(cmp)
    comp = tmp_path / "composite"
    script = tmp_path / "hop_then_settle.motion"
    script.write_text("phase hop = dcm_x * (dtime ~= 0.8)\nphase settle = max_t(cm_z)\n"
                      "total = (1 + hop) * (1 + settle)\n")
    best = [str(cmp / "best" / f"{fam}-seed0.json") for fam in ("gp", "bsr-time")]
    assert compose([str(script), "--controllers", *best, "--arrays", "4", "--rounds", "3", "--seconds", "2", "--transitions", "0.8",
                    "--out", str(comp), "--no-artifacts", "--quiet"]) == 0
    write_report(comp)
    DOCS_IMAGES.mkdir(exist_ok=True)
    _shot(browser, lamp / "report.html", DOCS_IMAGES / "report_run2d.png", 0.45, film=True)
    _shot(browser, herman / "report.html", DOCS_IMAGES / "report_run3d.png", 0.8)
    _shot(browser, cmp / "report.html", DOCS_IMAGES / "report_compare.png", 0.45, height=1300)
    _shot(browser, comp / "report.html", DOCS_IMAGES / "report_composite.png", 0.55, height=800)
