#!/usr/bin/python3
"""Browser tests of `soadyn view`, in headless chromium driven over the DevTools protocol.

For every scenario in scenarios/ (and a URDF arm with visual primitives): run it, write its page
(checked < 5 MB), open the page at #t=a (it must open paused at a), screenshot the scene with the
bodies shown and hidden (the bodies must cover part of it), move to #t=b and screenshot again (the
bodies must have moved), and check that the console logged no error and that the page requested
nothing.  The frames a run logged (view_visuals.yaml's log: frames:) are drawn as named triads
where the run file puts them, and move.  The joint limits' events (panda_gripper.yaml) are marked over
the timeline where the slider means their times, listed, dashed on the plots, and seek on a click.  Then: keyboard and plot clicks drive playback; a missing
URDF and bad files are refused with one clear line; and the checks themselves catch an error and a network request injected into
a copy of a page.

Environment: SOADYN (the executable), SOADYN_SOURCE_DIR; optional argument --save DIR writes one
small screenshot per scene there (the README's pictures).  Exit 77 (skipped) without chromium.
"""
import io
import json
import os
import shutil
import subprocess
import sys
import tempfile

SOURCE = os.environ.get("SOADYN_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(SOURCE, "tools", "view"))
from cdp import Browser, find_chromium  # noqa: E402

import numpy as np  # noqa: E402
from PIL import Image  # noqa: E402

SOADYN = os.environ.get("SOADYN", os.path.join(SOURCE, "build", "soadyn"))
MAX_PAGE_BYTES = 5_000_000
failures = []


def check(ok, what):
    print(("ok    " if ok else "FAIL  ") + what, flush=True)
    if not ok:
        failures.append(what)
    return ok


def run(*args, expect=0):
    p = subprocess.run([SOADYN, *args], capture_output=True, text=True, timeout=600)
    if p.returncode != expect:
        raise RuntimeError(f"soadyn {' '.join(args)}: exit {p.returncode}, expected {expect}\n{p.stdout}{p.stderr}")
    return p


def pixels(png):
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(np.int32)


def changed(a, b, rect):
    """Fraction of the pixels in rect (x, y, w, h) whose colour differs by more than 40 (sum over RGB)."""
    x, y, w, h = rect
    d = np.abs(a[y:y + h, x:x + w] - b[y:y + h, x:x + w]).sum(axis=2)
    return float((d > 40).mean())


def wait_render(b, t):
    b.wait_for(f"soadynView.renderedT !== null && Math.abs(soadynView.renderedT - ({t})) < 1e-9", timeout=30)


def act(b, expression):
    """Evaluate expression in the page, then wait until the page has drawn a new frame."""
    n = b.evaluate(f"(() => {{ const n = soadynView.renders; {expression}; return n; }})()")
    b.wait_for(f"soadynView.renders > {n}", timeout=30)


def canvas_rect(b):
    r = b.evaluate("(() => { const r = document.querySelector('#scene-pane canvas').getBoundingClientRect();"
                   " return [r.left, r.top, r.width, r.height]; })()")
    return tuple(int(round(v)) for v in r)


def check_scene(b, page, name, save_dir):
    """Load page, screenshots at two times; True if every check passed."""
    url = "file://" + os.path.abspath(page)
    ok = True
    b.navigate(url + "#t=0")
    b.wait_for("window.soadynView && soadynView.ready", timeout=60)
    st = b.evaluate("soadynView.state()")
    t0, t1 = st["t0"], st["t1"]
    ta = t0 + 0.15 * (t1 - t0)
    # a fresh load at #t=ta opens paused there
    b.navigate(url + f"#t={ta!r}")
    b.wait_for("window.soadynView && soadynView.ready", timeout=60)
    wait_render(b, ta)
    st = b.evaluate("soadynView.state()")
    ok &= check(not st["playing"] and abs(st["t"] - ta) < 1e-9 and st["speed"] == 1,
                f"{name}: #t={ta:.4g} opens paused at that time, speed x1 (got {st})")
    rect = canvas_rect(b)
    act(b, "soadynView.setTrailSeconds(0)")
    shot_a = pixels(b.screenshot())
    act(b, "soadynView.showBodies(false)")
    shot_hidden = pixels(b.screenshot())
    act(b, "soadynView.showBodies(true)")
    covered = changed(shot_a, shot_hidden, rect)
    # a later time, through the fragment of the open page; a periodic motion may come back to the
    # same pose, so up to three times are tried
    for tb in (t0 + f * (t1 - t0) for f in (0.55, 0.71, 0.87)):
        b.evaluate(f"location.hash = '#t={tb!r}'")
        wait_render(b, tb)
        shot_b = pixels(b.screenshot())
        moved = changed(shot_a, shot_b, rect)
        if moved > 0.002:
            break
    ok &= check(covered > 0.002, f"{name}: the bodies cover {100 * covered:.2f}% of the scene at t = {ta:.4g} s (> 0.2%)")
    ok &= check(moved > 0.002, f"{name}: {100 * moved:.2f}% of the scene changed between t = {ta:.4g} s and "
                               f"{tb:.4g} s (> 0.2%: the bodies moved)")
    b.pump(0.3)
    errors = b.console_errors()
    ok &= check(not errors, f"{name}: no console error" + (f" (got {errors})" if errors else ""))
    requests = b.requests(url)
    ok &= check(not requests, f"{name}: no network request" + (f" (got {requests})" if requests else ""))
    if save_dir:
        act(b, "soadynView.setTrailSeconds(4)")
        img = Image.open(io.BytesIO(b.screenshot())).convert("RGB").resize((960, 540), Image.LANCZOS)
        img.quantize(colors=256, method=Image.MEDIANCUT, dither=Image.NONE).save(
            os.path.join(save_dir, f"view_{name}.png"), optimize=True)
    return ok


def check_named_frames(b, page, h5):
    """The frames the run logged (view_visuals.yaml's log: frames:) are drawn as triads where the
    run file puts them, with their names, and move with the playback."""
    import h5py
    with h5py.File(h5, "r") as f:
        names = [n.decode() if isinstance(n, bytes) else n for n in f["frames/names"][:]]
        t, pos, att = f["time"][:], f["frames/position"][:], f["frames/orientation"][:]
    b.navigate("file://" + os.path.abspath(page) + "#t=0")
    b.wait_for("window.soadynView && soadynView.ready", timeout=60)
    wait_render(b, float(t[0]))
    check(b.evaluate("soadynView.counts().namedFrames") == len(names), f"view_visuals: {len(names)} logged frames drawn")
    note = b.evaluate("document.getElementById('frames-note').textContent")
    check(all(n in note for n in names), f"view_visuals: the legend names the logged frames ({note!r})")
    drawn = {}
    for row in (0, len(t) - 1):  # the first and the last sample are always shown
        b.evaluate(f"soadynView.seek({float(t[row])!r})")
        wait_render(b, float(t[row]))
        drawn[row] = b.evaluate("soadynView.namedFrames()")
        check([d["name"] for d in drawn[row]] == names, f"view_visuals: triads named {names}")
        for j, d in enumerate(drawn[row]):
            dp = float(np.abs(np.array(d["position"]) - pos[row, j]).max())
            x, y, z, w = d["quaternion"]
            dq = float(min(np.abs(np.array([w, x, y, z]) - s * att[row, j]).max() for s in (1, -1)))
            check(dp < 1e-5 and dq < 1e-5 and d["visible"],
                  f"view_visuals: triad {d['name']} at t = {t[row]:.3g} s where the run logged it "
                  f"(position {dp:.1e} m, quaternion {dq:.1e} off; float32)")
    last = len(t) - 1
    moved = [float(np.linalg.norm(np.array(drawn[last][j]["position"]) - np.array(drawn[0][j]["position"])))
             for j in range(len(names))]
    check(min(moved) > 0.05, f"view_visuals: the triads moved {', '.join(f'{m:.3f}' for m in moved)} m over the run (> 0.05)")
    # on screen: with the bodies hidden, the triads cover part of the scene, and move there
    rect = canvas_rect(b)
    act(b, "soadynView.showBodies(false); soadynView.setTrailSeconds(0)")
    shot_last = pixels(b.screenshot())
    act(b, "soadynView.showNamedFrames(false)")
    shot_none = pixels(b.screenshot())
    act(b, "soadynView.showNamedFrames(true)")
    covered = changed(shot_last, shot_none, rect)
    check(covered > 0.0005, f"view_visuals: the triads and labels cover {100 * covered:.3f}% of the scene (> 0.05%)")
    b.evaluate(f"soadynView.seek({float(t[0])!r})")
    wait_render(b, float(t[0]))
    shot_first = pixels(b.screenshot())
    moved_px = changed(shot_first, shot_last, rect)
    check(moved_px > 0.0005, f"view_visuals: {100 * moved_px:.3f}% of the scene changed with only the triads drawn "
                             f"between t = {t[0]:.3g} s and {t[last]:.3g} s (> 0.05%: they moved)")
    act(b, "soadynView.showBodies(true)")


def check_events(b, page, h5):
    """The joint limits' events of a run (panda_gripper.yaml: both fingers reach their stops and
    hold) are marked over the timeline where they happened, listed, drawn on the plots, and a click
    on a mark seeks to the event; the energy balance counts what the impacts took."""
    import h5py
    with h5py.File(h5, "r") as f:
        ev, t = f["events"][:], f["time"][:]
    b.navigate("file://" + os.path.abspath(page) + "#t=0")
    b.wait_for("window.soadynView && soadynView.ready", timeout=60)
    wait_render(b, float(t[0]))
    drawn = b.evaluate("soadynView.events()")
    check(len(drawn) == len(ev) > 0, f"panda_gripper: {len(drawn)} events drawn, the run file has {len(ev)}")
    t0, t1 = float(t[0]), float(t[-1])
    # each mark sits where the slider means its time: a click on the slider at the mark's x (marks
    # made transparent to the mouse) seeks to the event's time, to within two pixels of the slider
    line = b.evaluate("soadynView.timeline()")
    b.evaluate("document.getElementById('event-marks').querySelectorAll('.event-mark').forEach((m) => { m.style.pointerEvents = 'none'; })")
    for d, row in zip(drawn, ev):
        b.evaluate("soadynView.seek(" + repr(t1) + ")")
        wait_render(b, t1)
        # two frames for the slider's thumb to be laid out at its new value: a press where the thumb
        # still seems to be (the previous event's x, two events share it) moves nothing.  Under
        # load that layout can lag further, so the press is repeated once if nothing moved
        b.evaluate("new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r)))", await_promise=True)
        for attempt in range(2):
            for kind in ("mousePressed", "mouseReleased"):
                b.send("Input.dispatchMouseEvent", {"type": kind, "x": d["x"], "y": d["y"], "button": "left", "clickCount": 1})
            try:
                b.wait_for("soadynView.state().t < " + repr(t1 / 2), timeout=15 if attempt == 0 else 30)
                break
            except Exception:
                if attempt == 1:
                    raise
                b.evaluate("new Promise((r) => setTimeout(r, 500))", await_promise=True)
        got = b.evaluate("soadynView.state().t")
        tol = 2 * (t1 - t0) / line["width"]
        check(abs(d["t"] - row[0]) < 1e-9 and abs(got - row[0]) < tol,
              f"panda_gripper: {d['joint']} {d['side']} {d['kind']} at t = {d['t']:.9g} s marked at x = {d['x']:.1f}; "
              f"the slider clicked there seeks to {got:.5f} s (within {tol:.5f} s)")
    b.evaluate("document.getElementById('event-marks').querySelectorAll('.event-mark').forEach((m) => { m.style.pointerEvents = ''; })")
    title = b.evaluate("document.getElementById('events-title').textContent")
    rows = b.evaluate("document.querySelectorAll('#events-list .event-row').length")
    check(str(len(ev)) in title and rows == len(ev), f"panda_gripper: the list says {title!r} and has {rows} rows")
    energy = b.evaluate("document.getElementById('energy-title').textContent")
    check("+ L" in energy, f"panda_gripper: the energy balance counts the impacts' loss ({energy!r})")
    # the dashed mark on the energy plot, at the event's time
    area = b.evaluate("soadynView.plotArea('energy')")
    shot = pixels(b.screenshot())
    y0, y1 = int(area["top"]) + 2, int(area["top"] + area["h"]) - 2

    def dashed(frac):  # share of the plot's height with the mark's colour (not the cursor's orange) at frac
        x = int(round(area["left"] + area["w"] * frac))
        strip = shot[y0:y1, x - 1:x + 2]
        return x, float(((strip[..., 0] > 150) & (strip[..., 1] < 130) & (strip[..., 2] > 90)).any(axis=1).mean())
    x, marked = dashed((ev[0][0] - t0) / (t1 - t0))
    xo, other = dashed(0.6)
    check(marked > 0.3 and other < 0.05, f"panda_gripper: the energy plot has a dashed mark at x = {x} ({100 * marked:.0f}% "
                                          f"of its height, > 30%) and none at x = {xo} ({100 * other:.0f}%)")
    # a click on the mark seeks there
    b.evaluate("soadynView.seek(" + repr(t1) + ")")
    wait_render(b, t1)
    n = b.evaluate("soadynView.renders")
    for kind in ("mousePressed", "mouseReleased"):
        b.send("Input.dispatchMouseEvent", {"type": kind, "x": drawn[0]["x"], "y": drawn[0]["y"], "button": "left", "clickCount": 1})
    b.wait_for(f"soadynView.renders > {n}", timeout=30)
    now = b.evaluate("soadynView.state().t")
    check(abs(now - ev[0][0]) < 1e-9, f"panda_gripper: a click on the first mark seeks to t = {now:.9g} s (event at {ev[0][0]:.9g} s)")


def check_controls(b, page):
    """Keyboard and plot clicks on an open page."""
    url = "file://" + os.path.abspath(page)
    b.navigate(url + "#t=1")
    b.wait_for("window.soadynView && soadynView.ready", timeout=60)
    wait_render(b, 1)

    def key(k, code, vk, shift=False):
        for kind in ("keyDown", "keyUp"):
            b.send("Input.dispatchKeyEvent", {"type": kind, "key": k, "code": code, "windowsVirtualKeyCode": vk,
                                              "modifiers": 8 if shift else 0})

    key(" ", "Space", 32)
    check(b.evaluate("soadynView.state().playing") is True, "space starts playback")
    key(" ", "Space", 32)
    check(b.evaluate("soadynView.state().playing") is False, "space pauses it")
    b.evaluate("soadynView.seek(1)")
    key("ArrowRight", "ArrowRight", 39)
    frames = b.evaluate("soadynView.state()")
    t_next = b.evaluate("soadynView.state().t")
    check(t_next > 1 and t_next - 1 < 2 * (frames["t1"] - frames["t0"]) / (frames["frames"] - 1),
          f"right arrow steps one frame (t 1 -> {t_next:.4g})")
    key("ArrowLeft", "ArrowLeft", 37)
    check(abs(b.evaluate("soadynView.state().t") - 1) < 1e-9, "left arrow steps back")
    key("ArrowRight", "ArrowRight", 39, shift=True)
    check(abs(b.evaluate("soadynView.state().t") - 2) < 1e-9, "shift + right arrow: +1 s")
    key("ArrowUp", "ArrowUp", 38)
    check(b.evaluate("soadynView.state().speed") == 2, "up arrow: speed x2")
    key("ArrowDown", "ArrowDown", 40)
    key("ArrowDown", "ArrowDown", 40)
    check(b.evaluate("soadynView.state().speed") == 0.5, "down arrow twice: speed x0.5")
    for plot in ("energy", "joint"):
        a = b.evaluate(f"soadynView.plotArea('{plot}')")
        x, y = a["left"] + 0.75 * a["w"], a["top"] + 0.5 * a["h"]
        for kind in ("mousePressed", "mouseReleased"):
            b.send("Input.dispatchMouseEvent", {"type": kind, "x": x, "y": y, "button": "left", "clickCount": 1})
        st = b.evaluate("soadynView.state()")
        expect = st["t0"] + 0.75 * (st["t1"] - st["t0"])
        check(abs(st["t"] - expect) < 0.01 * (st["t1"] - st["t0"]) and not st["playing"],
              f"a click at 3/4 of the {plot} plot seeks to t = {st['t']:.4g} s (expected {expect:.4g})")
    # picking: a click on body 0 puts the trail behind it
    b.evaluate("soadynView.seek(2)")
    wait_render(b, 2)
    at = b.evaluate("soadynView.screenOf(0)")
    for kind in ("mousePressed", "mouseReleased"):
        b.send("Input.dispatchMouseEvent", {"type": kind, "x": at["x"], "y": at["y"], "button": "left", "clickCount": 1})
    check(b.evaluate("soadynView.counts().trailBody") == 0, "a click on body 0 puts the trail behind it")
    # the camera: a drag orbits, the wheel zooms
    c0 = b.evaluate("soadynView.camera()")
    x, y = at["x"] + 60, at["y"] + 40
    b.send("Input.dispatchMouseEvent", {"type": "mousePressed", "x": x, "y": y, "button": "left", "clickCount": 1})
    for k in range(1, 6):
        b.send("Input.dispatchMouseEvent", {"type": "mouseMoved", "x": x + 20 * k, "y": y, "button": "left", "buttons": 1})
    b.send("Input.dispatchMouseEvent", {"type": "mouseReleased", "x": x + 100, "y": y, "button": "left", "clickCount": 1})
    c1 = b.evaluate("soadynView.camera()")
    dist = lambda c: float(np.linalg.norm(np.subtract(c["position"], c["target"])))
    check(np.linalg.norm(np.subtract(c0["position"], c1["position"])) > 1e-3 * dist(c0) and abs(dist(c1) - dist(c0)) < 1e-6 * dist(c0),
          "a drag orbits the camera (same distance to the target, new position)")
    b.send("Input.dispatchMouseEvent", {"type": "mouseWheel", "x": x, "y": y, "deltaX": 0, "deltaY": -300})
    b.pump(0.2)
    c2 = b.evaluate("soadynView.camera()")
    check(dist(c2) < 0.99 * dist(c1), f"the wheel zooms in (distance {dist(c1):.3g} -> {dist(c2):.3g})")
    b.pump(0.2)
    check(not b.console_errors(), "no console error while driving the page")


def check_detectors(b, page, tmp):
    """The console and network checks catch what they are meant to catch."""
    html = open(page, encoding="utf-8").read()
    inject = '<img src="http://127.0.0.1:9/probe.png"><script>console.error("probe error")</script>'
    with_csp = os.path.join(tmp, "probe_csp.html")
    open(with_csp, "w", encoding="utf-8").write(html.replace("<body>", "<body>" + inject, 1))
    b.navigate("file://" + with_csp)
    b.pump(0.5)
    errors = b.console_errors()
    check(any("probe error" in e for e in errors), "detector: a console.error in the page is caught")
    check(any("Content Security Policy" in e for e in errors), "detector: the page's CSP refuses an outside image")
    start = html.index('<meta http-equiv="Content-Security-Policy"')
    no_csp = os.path.join(tmp, "probe_nocsp.html")
    stripped = html[:start] + html[html.index(">", start) + 1:]
    open(no_csp, "w", encoding="utf-8").write(stripped.replace("<body>", "<body>" + inject, 1))
    b.navigate("file://" + no_csp)
    b.pump(0.5)
    check(any("127.0.0.1:9" in u for u in b.requests("file://" + no_csp)),
          "detector: without the CSP, the outside request is caught on the network")


def check_cli_errors(tmp):
    p = run("view", os.path.join(tmp, "missing.h5"), expect=2)
    check("missing.h5: cannot open the file (no such file or directory)" in p.stderr and p.stderr.count("\n") == 1,
          f"missing run file: {p.stderr.strip()}")
    p = run("view", os.path.join(SOURCE, "scenarios", "double_pendulum.yaml"), "-o", os.path.join(tmp, "x.html"), expect=2)
    check("not an HDF5 file" in p.stderr, f"not a run file: {p.stderr.strip()}")
    # a run whose scenario and URDF have gone: the page from the text stored in the run, visuals included
    import h5py
    d = os.path.join(tmp, "moved")
    os.makedirs(d)
    for f in ("view_visuals.yaml", "view_visuals.urdf"):
        shutil.copy(os.path.join(SOURCE, "tests", "data", f), d)
    run("run", os.path.join(d, "view_visuals.yaml"), "-q", "--t-end", "0.1", "-o", os.path.join(d, "run.h5"))
    shutil.copy(os.path.join(d, "run.h5"), os.path.join(d, "old.h5"))
    for f in ("view_visuals.yaml", "view_visuals.urdf"):
        os.rename(os.path.join(d, f), os.path.join(d, f + ".gone"))
    p = run("view", os.path.join(d, "run.h5"))
    with open(os.path.join(d, "run.html"), encoding="utf-8") as f:
        page = f.read()
    # (its mesh, package://none/link2.stl, is nowhere: one note says so, and nothing else is said)
    notes = p.stderr.splitlines()
    check(len(notes) == 1 and "package://none/link2.stl drawn as its body's default shape" in notes[0] and
          '"kind":"cylinder"' in page, f"URDF gone: the page from the stored URDF ({p.stderr.strip()})")
    # a file from before /robot (layout 3): view reads nothing but the run file, so it is refused in
    # one line, whether the URDF is on disk or not
    with h5py.File(os.path.join(d, "old.h5"), "r+") as f:
        del f["robot"]
    for state in ("gone", "back"):
        p = run("view", os.path.join(d, "old.h5"), expect=2)
        check("holds no robot file" in p.stderr and "cannot rebuild the run's model" in p.stderr and
              p.stderr.count("\n") == 1, f"old file, URDF {state}: {p.stderr.strip()}")
        check(not os.path.exists(os.path.join(d, "old.html")), f"old file, URDF {state}: no page written")
        for f in ("view_visuals.yaml", "view_visuals.urdf"):
            if state == "gone":
                os.rename(os.path.join(d, f + ".gone"), os.path.join(d, f))
    # a run that went unstable: shown up to its last finite row, with a note
    src = os.path.join(tmp, "double_pendulum.h5")
    bad = os.path.join(tmp, "unstable.h5")
    shutil.copy(src, bad)
    with h5py.File(bad, "r+") as f:
        n = f["q"].shape[0]
        if "samples" in f:  # /q is a view of /samples' columns 1 ... nq
            f["samples"][n // 2:, 1] = np.nan
        else:
            f["q"][n // 2:, 0] = np.nan
        t_bad = float(f["time"][n // 2])
    p = run("view", bad, "-q")
    check(f"not finite from t = {t_bad:g} s on" in p.stderr and os.path.exists(bad[:-3] + ".html"),
          f"non-finite rows at the end: page up to them ({p.stderr.strip()})")
    # the scenario's text as a variable-length UTF-8 dataset, and (older files) as a root attribute:
    # layout 4 and before (layout 5 writes no variable-length string, and refuses one)
    with h5py.File(src, "r") as f:
        text = f["scenario"][()] if "scenario" in f else f.attrs["scenario"]
    text = text.decode() if isinstance(text, bytes) else text
    for where in ("dataset", "attribute"):
        moved = os.path.join(tmp, f"scenario_{where}.h5")
        shutil.copy(src, moved)
        with h5py.File(moved, "r+") as f:
            if "scenario" in f:
                del f["scenario"]
            if "scenario" in f.attrs:
                del f.attrs["scenario"]
            if where == "dataset":
                f["scenario"] = text
            else:
                f.attrs["scenario"] = text
            f.attrs["layout_version"] = 4
        p = subprocess.run([SOADYN, "view", moved, "-q"], capture_output=True, text=True)
        check(p.returncode == 0 and os.path.getsize(moved[:-3] + ".html") > 0,
              f"scenario stored as a variable-length {where}: read as well ({p.stderr.strip()})")
    with open(os.path.join(tmp, "double_pendulum.html"), encoding="utf-8") as f:
        check('"status":"completed"' in f.read(), "the run's status reaches the page")


def main():
    save_dir = None
    if "--save" in sys.argv:
        save_dir = sys.argv[sys.argv.index("--save") + 1]
        os.makedirs(save_dir, exist_ok=True)
    if not find_chromium():
        print("chromium not found: skipped (tools/setup.sh installs it)")
        return 77
    tmp = tempfile.mkdtemp(prefix="soadyn-view-test-")
    try:
        scenes = sorted(os.path.join(SOURCE, "scenarios", f) for f in os.listdir(os.path.join(SOURCE, "scenarios"))
                        if f.endswith(".yaml") and not f.endswith(".sweep.yaml"))
        scenes.append(os.path.join(SOURCE, "tests", "data", "view_visuals.yaml"))
        pages = {}
        for sc in scenes:
            name = os.path.splitext(os.path.basename(sc))[0]
            h5, page = os.path.join(tmp, name + ".h5"), os.path.join(tmp, name + ".html")
            run("run", sc, "-q", "-o", h5)
            out = run("view", h5, "-o", page).stdout
            size = os.path.getsize(page)
            check(size < MAX_PAGE_BYTES, f"{name}: page {size / 1e6:.2f} MB (< 5 MB); {out.splitlines()[2].split(None, 1)[1]}")
            pages[name] = page
        with Browser() as b:
            b.open_page()
            for name, page in pages.items():
                check_scene(b, page, name, save_dir)
            counts = None
            b.navigate("file://" + os.path.abspath(pages["view_visuals"]))
            b.wait_for("window.soadynView && soadynView.ready", timeout=60)
            counts = b.evaluate("soadynView.counts()")
            # box on the world-welded base, cylinder on link1, sphere on the welded tool; link2's mesh file
            # does not exist: link2 is drawn in its default shape, and the page's note says why
            check(counts["visuals"] == 3, f"view_visuals: 3 URDF primitives drawn (got {counts['visuals']})")
            check(counts["meshes"] == 0 and counts["fellBack"] == [1] and len(counts["meshErrors"]) == 1 and
                  "package://none/link2.stl: not found" in counts["meshErrors"][0],
                  f"view_visuals: link2's missing mesh named, link2 in its default shape ({counts['meshErrors']})")
            check_named_frames(b, pages["view_visuals"], os.path.join(tmp, "view_visuals.h5"))
            check_events(b, pages["panda_gripper"], os.path.join(tmp, "panda_gripper.h5"))
            check_controls(b, pages["double_pendulum"])
            check_detectors(b, pages["double_pendulum"], tmp)
        check_cli_errors(tmp)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    print(f"\n{len(failures)} failure(s)" if failures else "\nall checks passed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
