"""`jointsim view` pages in a real browser: headless Chromium (Debian's chromium and chromium-driver, driven by
Selenium) opens each page with the network disabled, scrubs to given times through the page's script interface
(window.jointsimView) and checks what it draws against independent numbers:

- the drawn tool centre point (three.js scene graph) against the library's forward kinematics (jointsim.frame_placement
  on the model file, at the logged joint angles) and, for the UR5, against the run's own logged TCP columns;
- every plot cursor readout against the CSV row it names (recomputed from the columns the page says it drew);
- the cursor and the animation following each other both ways (a time set by the page's interface moves every cursor;
  a mouse over a plot moves the arm);
- no console error, no request for any resource, and a hostile run folder's markup shown as text, never run.

A screenshot of each page goes to JOINTSIM_ARTEFACT_DIR (scripts/python-test.sh sets build/test-artefacts), else to
the test's temporary folder."""
import csv
import json
import math
import os
import pathlib
import shutil
import subprocess

import numpy as np
import pytest

import jointsim

CHROMIUM = shutil.which("chromium")
DRIVER = shutil.which("chromedriver")


def _browser_or_skip():
    if CHROMIUM and DRIVER:
        return
    message = "headless Chromium and chromedriver are needed (scripts/install-deps.sh --test: chromium chromium-driver)"
    if os.environ.get("CI"):
        pytest.fail(message)
    pytest.skip(message)


@pytest.fixture(scope="module")
def browser():
    _browser_or_skip()
    webdriver = pytest.importorskip("selenium.webdriver")
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for arg in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--enable-unsafe-swiftshader",
                "--use-angle=swiftshader", "--window-size=1600,1100", "--proxy-server=127.0.0.1:9",
                "--proxy-bypass-list=<-loopback>"):
        options.add_argument(arg)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(service=Service(DRIVER), options=options)
    # The network off for every page this browser opens (the page must work without it).
    driver.execute_cdp_cmd("Network.enable", {})
    driver.execute_cdp_cmd("Network.emulateNetworkConditions",
                           {"offline": True, "latency": 0, "downloadThroughput": -1, "uploadThroughput": -1})
    yield driver
    driver.quit()


@pytest.fixture(scope="module")
def runs(cli, root, tmp_path_factory):
    """The four runs of the acceptance criteria, run by the CLI, and their pages written by `jointsim view`."""
    out = tmp_path_factory.mktemp("view_runs")
    cfg = root / "config"
    for name in ("ur5_excitation", "irb140_clamping", "robotr3_full_robot"):
        subprocess.run([str(cli), "run", str(cfg / "experiments" / f"{name}.yaml"), "-o", str(out / name)],
                       check=True, capture_output=True)
    subprocess.run([str(cli), "batch", str(cfg / "sweeps" / "ur5_faults.yaml"), "-j", "2", "-o", str(out / "sweep")],
                   check=True, capture_output=True)
    pages = {}
    for name in ("ur5_excitation", "irb140_clamping", "robotr3_full_robot", "sweep"):
        r = subprocess.run([str(cli), "view", str(out / name), "-o", str(out / f"{name}.html")], check=True,
                           capture_output=True, text=True)
        assert "page:" in r.stdout
        pages[name] = out / f"{name}.html"
    return out, pages


def _artefact(tmp_path: pathlib.Path, name: str) -> pathlib.Path:
    d = pathlib.Path(os.environ.get("JOINTSIM_ARTEFACT_DIR", tmp_path))
    d.mkdir(parents=True, exist_ok=True)
    return d / name


def _open(driver, page: pathlib.Path):
    driver.get_log("browser")  # drop what earlier pages logged
    driver.get(page.resolve().as_uri())
    state = driver.execute_script("const v = window.jointsimView; return v ? [v.ready, v.errors] : null;")
    assert state is not None, "the page script did not run"
    assert state == [True, []], state


def _no_console_error(driver):
    severe = [e for e in driver.get_log("browser") if e.get("level") == "SEVERE"]
    assert severe == [], severe


def _no_request(driver):
    # Everything is inline: the page asked the network for nothing (it is off anyway).
    assert driver.execute_script("return performance.getEntriesByType('resource').map(e => e.name);") == []


def _read_csv(path: pathlib.Path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    names = [h.split("[")[0] for h in rows[0]]
    data = np.array([[float(v) for v in r] for r in rows[1:]])
    return names, data


def _tcp_fk(model, frame, q):
    return np.asarray(jointsim.frame_placement(model, q, frame))[:3, 3]


def _check_page(driver, page, csv_path, robot_file, times, tmp_path, shot, tcp_columns=None):
    _open(driver, page)
    data = driver.execute_script("return window.jointsimView.data;")
    assert data["arm"] is not None, data.get("arm_note")
    names, log = _read_csv(csv_path)
    t_col = names.index("time")
    model = jointsim.load_robot(robot_file)
    tcp_frame = data["arm"]["tcp"]["name"]
    angle_cols = [names.index(j["column"]) for j in data["arm"]["joints"]]
    # The readouts are checked on the first figure with time plots (a clamping run opens on its curves in the plane).
    figures = data["runs"][0]["figures"]
    first_timed = next(k for k, f in enumerate(figures) if any(p["time_axis"] for p in f["panels"]))
    driver.execute_script("window.jointsimView.selectFigure(arguments[0]);", first_timed)
    for t in times:
        row = int(np.argmin(np.abs(log[:, t_col] - t)))
        t_row = float(log[row, t_col])
        assert driver.execute_script("return window.jointsimView.setTime(arguments[0]);", t_row) == pytest.approx(t_row)
        drawn = np.array(driver.execute_script("return window.jointsimView.tcpPosition();"))
        fk = _tcp_fk(model, tcp_frame, log[row, angle_cols])
        assert np.max(np.abs(drawn - fk)) < 1e-9, (t_row, drawn, fk)
        if tcp_columns:
            logged = log[row, [names.index(c) for c in tcp_columns]]
            assert np.max(np.abs(drawn - logged)) < 1e-9, (t_row, drawn, logged)
        # Every time panel's cursor sits at the time, and each readout value is the CSV value of the row it names.
        panels = driver.execute_script("return window.jointsimView.panels();")
        checked = 0
        for k, p in enumerate(panels):
            if not p["time"]:
                continue
            ro = driver.execute_script("return window.jointsimView.readout(arguments[0]);", k)
            assert ro["cursor"] == pytest.approx(t_row)
            assert ro["text"].startswith("t = ")
            for v in ro["values"]:
                assert v["column"], v
                series = _series_spec(data, p, v)
                # The readout names the drawn sample nearest the cursor...
                xs = np.array([np.nan if x is None else x for x in series["x"]])
                assert abs(v["t"] - t_row) == pytest.approx(np.nanmin(np.abs(xs - t_row)), abs=1e-12), (t_row, v)
                # ...and its value is that of the CSV row at the sample's time.
                r = int(np.flatnonzero(log[:, t_col] == v["t"])[0])
                y = log[r, names.index(series["y_col"])]
                if series.get("y_minus_col"):
                    y -= log[r, names.index(series["y_minus_col"])]
                y = (y - series["offset"]) * series["factor"]
                # The page keeps 8 significant digits of a plotted value (the readout shows 6).
                assert v["value"] == pytest.approx(y, rel=1e-7, abs=1e-300), (p["title"], v)
                if v["unit"]:
                    assert v["unit"] in ro["text"]
                checked += 1
        assert checked > 0
    path = _artefact(tmp_path, shot)
    driver.save_screenshot(str(path))
    assert path.stat().st_size > 10_000
    assert driver.execute_script("return window.jointsimView.webgl();"), "WebGL (SwiftShader) was not available"
    _no_console_error(driver)
    _no_request(driver)
    return data


def _series_spec(data, panel, value):
    """The series of the shown figure that a readout value belongs to (by column and title)."""
    run = data["runs"][0]
    for fig in [run["figures"][panel["figure"]]]:
        for p in fig["panels"]:
            if p["title"] != panel["title"]:
                continue
            for s in p["series"]:
                if s.get("y_col") == value["column"] and (s.get("title") or s.get("y_col")) == value["series"]:
                    return s
    raise AssertionError(f"no series for {value}")


def test_ur5_excitation_page_draws_the_logged_kinematics_and_csv_values(browser, runs, root, tmp_path):
    out, pages = runs
    data = _check_page(browser, pages["ur5_excitation"], out / "ur5_excitation" / "ur5_excitation.csv",
                       root / "config" / "robots" / "ur5.yaml", [0.0, 2.5, 7.314, 10.0], tmp_path,
                       "view_ur5_excitation.png", tcp_columns=["tcp_x", "tcp_y", "tcp_z"])
    # Every figure of the type is offered; a second one (currents) reads back as the CSV too.
    titles = [f["title"] for f in data["runs"][0]["figures"]]
    assert len(titles) >= 3
    k = next(i for i, t in enumerate(titles) if "current" in t.lower())
    browser.execute_script("window.jointsimView.selectFigure(arguments[0]);", k)
    browser.execute_script("window.jointsimView.setTime(4.0);")
    ro = browser.execute_script("return window.jointsimView.readout(0);")
    assert ro["cursor"] == pytest.approx(4.0) and " A" in ro["text"]


def test_irb140_clamping_page_draws_the_clamp_and_the_curves(browser, runs, root, tmp_path):
    out, pages = runs
    # The page opens on the figure that characterises a clamping run: its curves in the plane, one panel per axis.
    _open(browser, pages["irb140_clamping"])
    shown = browser.execute_script("return window.jointsimView.panels();")
    assert len(shown) == 6 and not any(p["time"] for p in shown)
    browser_data = _check_page(browser, pages["irb140_clamping"], out / "irb140_clamping" / "irb140_clamping.csv",
                               root / "config" / "robots" / "irb140.yaml", [0.0, 1.2, 3.0], tmp_path,
                               "view_irb140_clamping.png")
    run = browser_data["runs"][0]
    assert browser_data["arm"]["clamped"] and run["motion"]["clamp"] is not None
    # The clamp is where the TCP was at the start; the clamped TCP stays within the clamp's compliance of it.
    clamp = np.array(run["motion"]["clamp"])
    for t in (0.0, 3.0):
        browser.execute_script("window.jointsimView.setTime(arguments[0]);", t)
        tcp = np.array(browser.execute_script("return window.jointsimView.tcpPosition();"))
        assert np.linalg.norm(tcp - clamp) < 1e-3
    # The figure that matters comes first: the clamping curves (motor torque against motor angle) in the plane.
    first = run["figures"][0]
    assert "clamping curves" in first["title"]
    assert not first["panels"][0]["time_axis"]


def test_robotr3_full_robot_page(browser, runs, root, tmp_path):
    out, pages = runs
    _check_page(browser, pages["robotr3_full_robot"], out / "robotr3_full_robot" / "robotr3_full_robot.csv",
                root / "config" / "robots" / "robotr3.yaml", [0.0, 0.5, 1.0, 1.8], tmp_path,
                "view_robotr3_full_robot.png")


def test_cursor_and_animation_follow_each_other(browser, runs):
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.keys import Keys

    _, pages = runs
    _open(browser, pages["robotr3_full_robot"])
    browser.execute_script("window.jointsimView.setTime(0.25);")
    overs = browser.find_elements("css selector", "#plots .u-over")
    assert overs
    over = overs[0]
    w = over.size["width"]
    # The mouse at 3/4 of the first plot's width: the arm follows the cursor (paused), every readout too.
    ActionChains(browser).move_to_element_with_offset(over, int(w * 0.25), 5).perform()
    t = browser.execute_script("return window.jointsimView.time();")
    assert t > 0.5
    for k, p in enumerate(browser.execute_script("return window.jointsimView.panels();")):
        if p["time"]:
            assert browser.execute_script("return window.jointsimView.readout(arguments[0]).cursor;", k) == \
                pytest.approx(t)
    # Zoom (wheel) and pan (shift-drag) of one plot apply to every time plot; a double-click resets them.
    full = browser.execute_script("return window.jointsimView.span(0);")
    for _ in range(3):  # one wheel step per call: uPlot applies a scale change in a microtask
        browser.execute_script("""const o = document.querySelectorAll('#plots .u-over')[0], r = o.getBoundingClientRect();
            o.dispatchEvent(new WheelEvent('wheel', {deltaY: -100, clientX: r.left + r.width / 2,
                                                     clientY: r.top + 10, bubbles: true, cancelable: true}));""")
    spans = [browser.execute_script("return window.jointsimView.span(arguments[0]);", k)
             for k, p in enumerate(browser.execute_script("return window.jointsimView.panels();")) if p["time"]]
    assert len(spans) >= 2 and all(sp == pytest.approx(spans[0]) for sp in spans)
    assert spans[0][1] - spans[0][0] == pytest.approx(0.8 ** 3 * (full[1] - full[0]), rel=1e-6)
    ActionChains(browser).key_down(Keys.SHIFT).move_to_element_with_offset(over, 0, 5).click_and_hold() \
        .move_by_offset(-int(w * 0.2), 0).release().key_up(Keys.SHIFT).perform()
    panned = browser.execute_script("return window.jointsimView.span(1);")
    assert panned[1] - panned[0] == pytest.approx(spans[0][1] - spans[0][0], rel=1e-6)
    assert panned[0] > spans[0][0]
    ActionChains(browser).double_click(over).perform()
    assert browser.execute_script("return window.jointsimView.span(1);") == pytest.approx(full)
    # Playing moves the time on.
    browser.execute_script("window.jointsimView.setTime(0); window.jointsimView.play(true);")
    browser.execute_script("return new Promise(r => setTimeout(r, 300));")
    assert browser.execute_script("window.jointsimView.play(false); return window.jointsimView.time();") > 0.05


def test_sweep_page_lists_the_runs_with_labels_and_overlays_them(browser, runs, root, tmp_path):
    out, pages = runs
    _open(browser, pages["sweep"])
    data = browser.execute_script("return window.jointsimView.data;")
    names = [r["name"] for r in data["runs"]]
    assert len(names) == 25 and names[0] == "nominal"
    rows = browser.find_elements("css selector", "#runs tr.run")
    assert len(rows) == 25
    header = [th.text for th in browser.find_elements("css selector", "#runs th")]
    assert {"fault_type", "fault_joint", "fault_severity"} <= set(header)
    # Every run's key signal is overlaid in one panel; choosing a run from the list animates that run.
    panels = browser.execute_script("return window.jointsimView.panels();")
    assert len(panels) == 1 and len(panels[0]["series"]) == 25
    k = names.index("backlash_add-elbow_joint-0.001")
    rows[k].click()
    assert "selected" in rows[k].get_attribute("class")
    names_csv, log = _read_csv(out / "sweep" / names[k] / "ur5_excitation.csv")
    model = jointsim.load_robot(root / "config" / "robots" / "ur5.yaml")
    for t in (0.5, 1.5):
        browser.execute_script("window.jointsimView.setTime(arguments[0]);", t)
        row = int(np.argmin(np.abs(log[:, 0] - t)))
        assert log[row, 0] == pytest.approx(t)
        q = log[row, [names_csv.index(j["column"]) for j in data["arm"]["joints"]]]
        drawn = np.array(browser.execute_script("return window.jointsimView.tcpPosition();"))
        assert np.max(np.abs(drawn - _tcp_fk(model, data["arm"]["tcp"]["name"], q))) < 1e-9
        ro = browser.execute_script("return window.jointsimView.readout(0);")
        v = ro["values"][k]
        assert v["series"] == names[k]
        assert names[k] + ":" in ro["text"]
    path = _artefact(tmp_path, "view_ur5_fault_sweep.png")
    browser.save_screenshot(str(path))
    _no_console_error(browser)
    _no_request(browser)


HOSTILE = '<img src=x onerror="window.pwned=1"><script>window.pwned=2</script>'


def _hostile_folder(base: pathlib.Path) -> pathlib.Path:
    """A run folder whose summary, column names and values are hostile, and a sweep around it."""
    run = base / "run"
    run.mkdir(parents=True)
    columns = ["time[s]", f"q_{HOSTILE}[rad]", "huge[N·m]", "odd</script><b>x</b>[A]"]
    with open(run / "evil.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(columns)
        for i, row in enumerate([[0, 1.0, 1e308, "nan"], [0.1, "inf", -1e308, 2.0], [0.2, "-inf", 5e-324, 3.0],
                                 [0.3, 2.0, 1e300, "nan"]]):
            w.writerow(row)
    summary = {"experiment": "evil", "type": HOSTILE, "status": f"ok{HOSTILE}", "csv": str(run / "evil.csv"),
               "reason": "</script><script>window.pwned=3</script>", "columns": columns,
               "parameters": {"config": {"experiment": {"name": "evil", "type": HOSTILE}}, HOSTILE: [HOSTILE, 1e308]}}
    (run / "summary.json").write_text(json.dumps(summary))
    sweep = base / "sweep"
    shutil.copytree(run, sweep / "evil")
    # A run whose log has a header only (no key signal to overlay, nothing to animate).
    (sweep / "empty").mkdir()
    (sweep / "empty" / "evil.csv").write_text("time[s],y[-]\n")
    (sweep / "empty" / "summary.json").write_text(json.dumps({"experiment": "evil", "type": "custom", "status": "ok"}))
    with open(sweep / "manifest.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["run", "status", "wall_time_s", "sim_time_s", "real_time_factor", "output_dir", "overrides",
                    "fault_type", "fault_joint", "design"])
        w.writerow(["evil", HOSTILE, "1", "0.3", "0.3", "evil", HOSTILE, HOSTILE, "</script>", "<!--"])
        w.writerow(["empty", "ok", "1", "0", "0", "empty", "", "", "", ""])
    return base


def test_hostile_folder_shows_its_markup_as_text_and_runs_none_of_it(browser, cli, tmp_path):
    base = _hostile_folder(tmp_path / "hostile")
    for folder in ("run", "sweep"):
        page = tmp_path / f"{folder}.html"
        subprocess.run([str(cli), "view", str(base / folder), "-o", str(page)], check=True, capture_output=True)
        html = page.read_text(encoding="utf-8")
        assert "window.pwned" in html  # the data is there, escaped inside the JSON
        assert "<script>window.pwned" not in html and "<img src=x" not in html
        _open(browser, page)
        assert browser.execute_script("return window.pwned === undefined;")
        assert browser.execute_script("return document.querySelectorAll('img, b, script:not([nonce]):not([type])')"
                                      ".length;") == 0
        text = browser.execute_script("return document.body.innerText;")
        assert HOSTILE in text
        data = browser.execute_script("return window.jointsimView.data;")
        assert data["arm"] is None and data["arm_note"]
        if folder == "sweep":  # the run without a log: listed, selectable, not overlaid
            assert len(data["runs"]) == 2
            assert len(browser.execute_script("return window.jointsimView.panels();")[0]["series"]) == 1
            browser.execute_script("window.jointsimView.selectRun(1); window.jointsimView.selectRun(0);")
            assert browser.execute_script("return window.jointsimView.errors;") == []
        browser.save_screenshot(str(_artefact(tmp_path, f"view_hostile_{folder}.png")))
        _no_console_error(browser)


def test_python_view_returns_the_page_and_writes_it(runs, tmp_path):
    out, _ = runs
    # Decimated to 50 slices: per slice at most a minimum, a maximum and a gap row (plus both ends) against time,
    # at most 100 evenly strided points (plus the last) of a curve in the plane (the clamping curves).
    for name in ("irb140_clamping", "robotr3_full_robot"):
        page = jointsim.view(out / name, columns=50, frames=100)
        start = page.index('id="jointsim-data">') + len('id="jointsim-data">')
        run = json.loads(page[start:page.index("</script>", start)])["runs"][0]
        for fig in run["figures"]:
            for p in fig["panels"]:
                for s in p["series"]:
                    n = len(s.get("xi", s.get("x")))
                    assert n <= (3 * 50 + 2 if p["time_axis"] else 2 * 50 + 1), (name, p["title"], n)
                    # At least one point per slice (stride ceil(n / 100) keeps >= 100 n / (n + 100) >= 50 of n >= 100).
                    assert n >= 50 or s.get("points"), (name, p["title"], n)
    page = jointsim.view(out / "robotr3_full_robot", output=tmp_path / "p.html", columns=50, frames=100)
    assert isinstance(page, str) and page.startswith("<!DOCTYPE html>")
    assert (tmp_path / "p.html").read_text(encoding="utf-8") == page
    assert "srcdoc=" in page._repr_html_()
    start = page.index('id="jointsim-data">') + len('id="jointsim-data">')
    data = json.loads(page[start:page.index("</script>", start)])
    run = data["runs"][0]
    assert len(run["motion"]["xi"]) <= 100 and len(run["time"]) <= 3 * 50 * 40 + 100
    with pytest.raises(jointsim.InputError, match="neither a run folder"):
        jointsim.view(tmp_path)
    with pytest.raises(jointsim.InputError, match="columns"):
        jointsim.view(out / "robotr3_full_robot", columns=1)


def test_rig_sweep_overlays_the_friction_maps_of_its_runs(browser, cli, root, tmp_path):
    """A sweep of friction-map rig runs: the friction map (the rig's figure in the plane) of every run, overlaid;
    every drawn point is a (velocity, friction torque) sample of that run's log."""
    sweep = tmp_path / "rig_sweep.yaml"
    sweep.write_text(f"""sweep:
  name: rig_sweep
  experiment: {root / 'config' / 'experiments' / 'lugre_friction_map.yaml'}
  set: {{duration: 60}}
grid:
  friction.model.sigma0: [150, 400]
""")
    out = tmp_path / "out"
    subprocess.run([str(cli), "batch", str(sweep), "-j", "2", "-o", str(out)], check=True, capture_output=True)
    subprocess.run([str(cli), "view", str(out), "-o", str(tmp_path / "rig.html")], check=True, capture_output=True)
    _open(browser, tmp_path / "rig.html")
    options = [o.text for o in browser.find_elements("css selector", "#figure-select option")]
    assert len(options) == 2 and "friction map (every run)" in options[1]
    assert [c.text for c in browser.find_elements("css selector", "#runs td")][2::3] == \
        ["friction.model.sigma0=150", "friction.model.sigma0=400"]
    browser.execute_script("window.jointsimView.selectFigure(1);")
    panels = browser.execute_script("return window.jointsimView.panels();")
    assert len(panels) == 1 and not panels[0]["time"]
    data = browser.execute_script("return window.jointsimView.data;")
    for run in data["runs"]:
        names, log = _read_csv(out / run["name"] / "lugre_friction_map.csv")
        samples = next(s for s in run["figures"][0]["panels"][0]["series"] if s.get("y_col"))
        assert len(samples["x"]) > 100
        xs, ys = log[:, names.index(samples["x_col"])], log[:, names.index(samples["y_col"])]
        for x, y in list(zip(samples["x"], samples["y"]))[::25]:
            assert np.min(np.abs(xs - x) + np.abs(ys - y) / 10) < 1e-6 * (1 + abs(x)), (x, y)
    assert len(panels[0]["series"]) == 2 * len([r for r in data["runs"] if r["figures"]])
    _no_console_error(browser)


def test_urdf_link_geometry_is_drawn_where_the_kinematics_put_it(browser, cli, root, tmp_path):
    """A URDF arm with visuals (box, cylinder, sphere, an STL found through package://, a box on a fixed child link,
    a missing mesh): each drawn shape's centre is where the library's forward kinematics puts that link's geometry."""
    data_dir = root / "tests" / "data" / "visual_arm"
    run = tmp_path / "run"
    subprocess.run([str(cli), "run", str(data_dir / "visual_arm_swing.yaml"), "-o", str(run)], check=True,
                   capture_output=True)
    subprocess.run([str(cli), "view", str(run), "-o", str(tmp_path / "arm.html")], check=True, capture_output=True)
    _open(browser, tmp_path / "arm.html")
    data = browser.execute_script("return window.jointsimView.data;")
    assert any("missing.stl" in n and "not found" in n for n in data["notes"])
    assert "missing.stl" in browser.execute_script("return document.getElementById('notes').innerText;")
    model = jointsim.load_robot(data_dir / "urdf" / "visual_arm.urdf")
    names, log = _read_csv(run / "visual_arm_swing.csv")
    rx = np.array([[1, 0, 0], [0, math.cos(0.3), -math.sin(0.3)], [0, math.sin(0.3), math.cos(0.3)]])
    # Each shape's centre in its link frame, from the URDF: origin + rotation · (centre of the geometry).
    expected_local = [("base_link", [0, 0, 0.025]), ("link1", [0, 0, 0.25]), ("link1", [0, 0, 0.5]),
                      ("link2", list(np.array([0.02, 0, 0]) + rx @ np.array([0.2, 0, 0]))), ("tool", [0, 0, 0.03])]
    for t in (0.0, 0.5, 1.0):
        row = int(np.argmin(np.abs(log[:, 0] - t)))
        browser.execute_script("window.jointsimView.setTime(arguments[0]);", float(log[row, 0]))
        q = log[row, [names.index("q_joint1"), names.index("q_joint2")]]
        drawn = browser.execute_script("return window.jointsimView.visuals();")
        assert [d["link"] for d in drawn] == [e[0] for e in expected_local]
        for d, (link, local) in zip(drawn, expected_local):
            T = np.asarray(jointsim.frame_placement(model, q, link))
            want = T[:3, :3] @ np.array(local, dtype=float) + T[:3, 3]
            # An STL holds float32 vertices (three.js keeps them so): 1e-6 m for the mesh, 1e-9 m for the primitives.
            tol = 1e-6 if link == "link2" else 1e-9
            assert np.max(np.abs(np.array(d["center"]) - want)) < tol, (t, link, d["center"], want)
    browser.save_screenshot(str(_artefact(tmp_path, "view_urdf_visuals.png")))
    _no_console_error(browser)
    _no_request(browser)


def test_hostile_joint_link_and_mesh_names_of_an_arm_stay_text(browser, cli, root, tmp_path):
    """The arm's own names (joints, links, meshes) reach the page too: markup in them is shown, never run."""
    pkg = tmp_path / "visual_arm"
    shutil.copytree(root / "tests" / "data" / "visual_arm", pkg)
    urdf = (pkg / "urdf" / "visual_arm.urdf").read_text()
    evil = 'x&lt;img src=x onerror=&quot;window.pwned=1&quot;&gt;'
    urdf = urdf.replace('name="joint1"', f'name="j{evil}"').replace('"link1"', f'"l{evil}"') \
        .replace("missing.stl", "missing&lt;script&gt;window.pwned=2&lt;/script&gt;.stl")
    (pkg / "urdf" / "visual_arm.urdf").write_text(urdf)
    run = tmp_path / "run"
    subprocess.run([str(cli), "run", str(pkg / "visual_arm_swing.yaml"), "-o", str(run)], check=True,
                   capture_output=True)
    subprocess.run([str(cli), "view", str(run), "-o", str(tmp_path / "arm.html")], check=True, capture_output=True)
    _open(browser, tmp_path / "arm.html")
    assert browser.execute_script("return window.pwned === undefined;")
    assert browser.execute_script("return document.querySelectorAll('img, script:not([nonce]):not([type])')"
                                  ".length;") == 0
    text = browser.execute_script("return document.body.innerText;")
    assert 'jx<img src=x onerror="window.pwned=1">' in text  # the joint's gauge
    assert "missing<script>window.pwned=2</script>.stl" in text  # the note on the mesh not found
    assert len(browser.execute_script("return window.jointsimView.visuals();")) == 5
    _no_console_error(browser)
