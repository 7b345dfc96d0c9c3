#!/usr/bin/python3
"""Browser tests of the meshes `soadyn view` draws, in headless chromium over the DevTools protocol.

The test writes its own meshes (tests/cli/mesh_files.py: boxes and a pyramid as binary and ASCII STL,
OBJ and Collada) and a URDF naming them by package://, a path relative to the URDF, file:// and
with scales; runs it, writes its page, and checks with pixels that each mesh is drawn in its colour
(a Collada file in its own material, not the URDF's) and that a file replaced by a larger one is
drawn larger.  Broken files (garbage, missing, a FIFO, malformed for the page's loaders) are drawn
as their bodies' default shape and named with the reason, with no console error.  Pointing at a
body shows its name; the plots' axes carry units; the inertia boxes are an option when visuals
exist.  An MJCF model's meshes (meshdir, mesh scale, geom and material colours) are drawn as
MuJoCo compiled them, where the model puts them.  No page requests anything.

Last, the page of a Panda-like arm (10 links, a binary STL of 40 000 triangles each, written here)
is made and opened: its size, load time, picking and frame costs are printed (src/cli/README.md
quotes them).  Environment: SOADYN (the executable), SOADYN_SOURCE_DIR.  Exit 77 (skipped) without
chromium.
"""
import base64
import io
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

SOURCE = os.environ.get("SOADYN_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(SOURCE, "tools", "view"))
sys.path.insert(0, os.path.join(SOURCE, "tests", "cli"))
from cdp import Browser, find_chromium  # noqa: E402
import mesh_files as mf  # noqa: E402

import numpy as np  # noqa: E402
from PIL import Image  # noqa: E402

SOADYN = os.environ.get("SOADYN", os.path.join(SOURCE, "build", "soadyn"))
failures = []

# the bodies of the URDF, their meshes and colours (hue in degrees); the Collada box has a magenta
# material of its own, so the cyan its URDF <material> gives must not be seen
BODIES = ["stl_bin", "stl_ascii", "obj", "dae", "big"]
HUES = {"stl_bin": 0, "stl_ascii": 120, "obj": 228, "dae": 300, "big": 57}
CYAN = 180


def check(ok, what):
    print(("ok    " if ok else "FAIL  ") + what, flush=True)
    if not ok:
        failures.append(what)
    return ok


def soadyn(*args, expect=0, timeout=120):
    p = subprocess.run([SOADYN, *args], capture_output=True, text=True, timeout=timeout)
    if p.returncode != expect:
        raise RuntimeError(f"soadyn {' '.join(args)}: exit {p.returncode}, expected {expect}\n{p.stdout}{p.stderr}")
    return p


def page_data(path):
    with open(path, encoding="utf-8") as f:
        text = f.read()
    return text, json.loads(re.search(r'<script type="application/json" id="soadyn-run">(.*?)</script>', text, re.S).group(1))


# --- the robot ------------------------------------------------------------------------------------

def write_meshbot(root):
    """ws/src/meshbot/{urdf/meshbot.urdf, meshes/*}: five bodies side by side on joints that gravity
    does not move (four about z, one sliding along x), each drawn by a mesh, and a world-welded base
    bar drawn by the same binary STL as two of them (three spellings of one file)"""
    pkg = os.path.join(root, "ws", "src", "meshbot")
    os.makedirs(os.path.join(pkg, "urdf"))
    os.makedirs(os.path.join(pkg, "meshes"))
    files = {"cube.stl": mf.stl_binary(mf.box()), "pyramid_ascii.stl": mf.stl_ascii(mf.pyramid()),
             "cube.obj": mf.obj(mf.box()), "box.dae": mf.dae(mf.box(), rgb=(0.85, 0.1, 0.85))}
    for name, data in files.items():
        with open(os.path.join(pkg, "meshes", name), "wb") as f:
            f.write(data)
    inertial = ('<inertial><mass value="1"/><inertia ixx="0.0067" iyy="0.0067" izz="0.0067" ixy="0" ixz="0" iyz="0"/>'
                '</inertial>')
    cube_file = "file://" + os.path.join(pkg, "meshes", "cube.stl")
    obj_file = "file://" + os.path.join(pkg, "meshes", "cube.obj")

    def link(name, mesh, scale, material):
        return (f'  <link name="{name}">{inertial}<visual><geometry><mesh filename="{mesh}" scale="{scale}"/></geometry>'
                f'{material}</visual></link>\n')

    def joint(name, child, y, kind="revolute", axis="0 0 1"):
        return (f'  <joint name="{name}" type="{kind}"><parent link="base"/><child link="{child}"/><origin xyz="0 {y} 0"/>'
                f'<axis xyz="{axis}"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>\n')
    urdf = ('<?xml version="1.0"?>\n<robot name="meshbot">\n'
            '  <material name="red"><color rgba="0.9 0.1 0.1 1"/></material>\n'
            f'  <link name="base"><visual><origin xyz="0 0.3 -0.3"/><geometry><mesh filename="{cube_file}" '
            'scale="0.1 2.6 0.02"/></geometry><material name="grey"><color rgba="0.5 0.5 0.5 1"/></material></visual></link>\n'
            + link("stl_bin", "package://meshbot/meshes/cube.stl", "0.2 0.2 0.2", '<material name="red"/>')
            + link("stl_ascii", "../meshes/pyramid_ascii.stl", "0.25 0.25 0.25",
                   '<material name="green"><color rgba="0.1 0.8 0.1 1"/></material>')
            + link("obj", obj_file, "0.2 0.2 0.2", '<material name="blue"><color rgba="0.1 0.2 0.9 1"/></material>')
            + link("dae", "package://meshbot/meshes/box.dae", "0.2 0.2 0.2",
                   '<material name="cyan"><color rgba="0.1 0.8 0.8 1"/></material>')
            + link("big", "../meshes/cube.stl", "0.4 0.4 0.4", '<material name="yellow"><color rgba="0.9 0.85 0.1 1"/></material>')
            + joint("j1", "stl_bin", -0.75) + joint("j2", "stl_ascii", -0.25) + joint("j3", "obj", 0.25)
            + joint("j4", "dae", 0.75, "prismatic", "1 0 0") + joint("j5", "big", 1.35)
            + '</robot>\n')
    path = os.path.join(pkg, "urdf", "meshbot.urdf")
    with open(path, "w") as f:
        f.write(urdf)
    return path, os.path.join(pkg, "meshes"), files


# --- pixels -----------------------------------------------------------------------------------------

def pixels(png):
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(np.float64) / 255


def hue_mask(img, hue, tol=14):
    """pixels of a saturated colour within tol degrees of hue"""
    mx, mn = img.max(axis=2), img.min(axis=2)
    d = np.where(mx - mn > 1e-9, mx - mn, 1)
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    h = np.where(mx == r, (g - b) / d % 6, np.where(mx == g, (b - r) / d + 2, (r - g) / d + 4)) * 60
    s = np.where(mx > 0, (mx - mn) / np.maximum(mx, 1e-9), 0)
    dh = np.abs((h - hue + 180) % 360 - 180)
    return (dh < tol) & (s > 0.45) & (mx > 0.15)


def canvas_rect(b):
    r = b.evaluate("(() => { const r = document.querySelector('#scene-pane canvas').getBoundingClientRect();"
                   " return [r.left, r.top, r.width, r.height]; })()")
    return tuple(int(round(v)) for v in r)


def act(b, expression):
    """evaluate, then wait until the page has drawn a new frame"""
    n = b.evaluate(f"(() => {{ const n = soadynView.renders; {expression}; return n; }})()")
    b.wait_for(f"soadynView.renders > {n}", timeout=30)


def open_page(b, page, t=0.1):
    b.navigate("file://" + os.path.abspath(page) + f"#t={t}")
    b.wait_for("window.soadynView && soadynView.ready", timeout=120)
    b.wait_for("soadynView.renders > 0", timeout=60)


def visual_pixels(b):
    """screenshots with only the visuals layer shown, and with nothing: the pixels the visuals drew,
    counted by hue"""
    x, y, w, h = canvas_rect(b)
    was = b.evaluate("soadynView.layers()")
    act(b, "soadynView.setTrailSeconds(0); ['skeleton', 'cm', 'boxes', 'axes'].forEach((l) => soadynView.showLayer(l, false));"
           " soadynView.showLayer('visuals', true)")
    on = pixels(b.screenshot())[y:y + h, x:x + w]
    act(b, "soadynView.showLayer('visuals', false)")
    off = pixels(b.screenshot())[y:y + h, x:x + w]
    act(b, "; ".join(f"soadynView.showLayer('{k}', {'true' if v else 'false'})" for k, v in was.items()))
    drawn = np.abs(on - off).sum(axis=2) > 0.15
    counts = {name: int((drawn & hue_mask(on, hue)).sum()) for name, hue in HUES.items()}
    counts["cyan"] = int((drawn & hue_mask(on, CYAN)).sum())
    counts["all"] = int(drawn.sum())
    return counts


def clean_browser(b, page, name):
    b.pump(0.3)
    errors = b.console_errors()
    check(not errors, f"{name}: no console error" + (f" (got {errors})" if errors else ""))
    requests = b.requests("file://" + os.path.abspath(page))
    check(not requests, f"{name}: no network request" + (f" (got {requests})" if requests else ""))


def hover(b, x, y):
    """move the pointer to (x, y); the label's text once the page has looked (None: no label)"""
    b.send("Input.dispatchMouseEvent", {"type": "mouseMoved", "x": x, "y": y})
    b.evaluate("new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r)))", await_promise=True)
    return b.evaluate("(() => { const l = document.getElementById('hover-label');"
                      " return l.style.display === 'block' ? l.textContent : null; })()")


# --- the checks -------------------------------------------------------------------------------------

def check_page_data(page, out):
    text, data = page_data(page)
    names = [m["name"] for m in data["meshes"]]
    check(len(names) == 4 and all(m["error"] is None for m in data["meshes"]),
          f"meshbot: 4 mesh files in the page, none refused ({names})")
    blocks = re.findall(r'<script type="text/plain" id="soadyn-mesh-(\d+)">', text)
    check(sorted(blocks) == ["0", "1", "2", "3"], f"meshbot: each file embedded once ({len(blocks)} blocks for 6 mesh visuals)")
    shapes = {b["name"]: b["visuals"] for b in data["bodies"]}
    check(shapes["big"][0]["size"] == [0.4, 0.4, 0.4] and shapes["stl_ascii"][0]["size"] == [0.25, 0.25, 0.25] and
          shapes["big"][0]["mesh"] == shapes["stl_bin"][0]["mesh"] == data["world_visuals"][0]["mesh"],
          "meshbot: the URDF's scales reach the page; package://, relative and file:// name one cube.stl")
    check("meshes                 4 file(s)" in out, f"meshbot: soadyn view's summary counts the mesh files ({out.splitlines()[3]!r})")


def check_good_page(b, page):
    open_page(b, page)
    counts = b.evaluate("soadynView.counts()")
    check(counts["meshes"] == 6 and counts["meshErrors"] == [] and counts["fellBack"] == [],
          f"meshbot: 6 mesh visuals drawn, none fell back ({counts['meshes']}, {counts['meshErrors']})")
    # the inertia boxes are an option when visuals exist; the keys b and v toggle
    layers = b.evaluate("soadynView.layers()")
    check(not layers["boxes"] and layers["visuals"], f"meshbot: visuals shown and inertia boxes hidden by default ({layers})")

    def key(k):
        for kind in ("keyDown", "keyUp"):
            b.send("Input.dispatchKeyEvent", {"type": kind, "key": k, "code": "Key" + k.upper(), "windowsVirtualKeyCode": ord(k.upper())})
    key("b")
    boxes_on = b.evaluate("soadynView.layers().boxes && document.getElementById('show-boxes').checked")
    key("b")
    key("v")
    visuals_off = b.evaluate("!soadynView.layers().visuals && !document.getElementById('show-visuals').checked")
    key("v")
    check(boxes_on and visuals_off and b.evaluate("soadynView.layers().visuals && !soadynView.layers().boxes"),
          "meshbot: key b shows the inertia boxes and v hides the visuals (and again: back)")
    help_text = b.evaluate("document.getElementById('keys').textContent")
    check("b inertia boxes" in help_text and "v visuals" in help_text, f"meshbot: the page's help lists the keys ({help_text!r})")
    px = visual_pixels(b)
    check(all(px[n] > 150 for n in BODIES), "meshbot: each mesh drawn in its colour: " + ", ".join(f"{n} {px[n]} px" for n in BODIES))
    check(px["big"] > 3 * px["stl_bin"], f"meshbot: cube.stl at scale 0.4 covers {px['big'] / px['stl_bin']:.1f} times what it "
                                          "covers at scale 0.2 (> 3: the URDF's scale is drawn)")
    check(px["cyan"] < 20, f"meshbot: the Collada box in its own material, not the URDF's cyan ({px['cyan']} cyan px)")
    # pointing at a body names it: with only the meshes drawn (the hit is a mesh's), then as opened
    act(b, "['skeleton', 'cm', 'axes'].forEach((l) => soadynView.showLayer(l, false))")
    for i, name in enumerate(BODIES):
        at = b.evaluate(f"soadynView.screenOf({i})")
        got = hover(b, at["x"], at["y"] + 3)
        check(got == name, f"meshbot: the pointer on the {name} mesh shows its name ({got!r})")
    x, y, w, h = canvas_rect(b)
    got = hover(b, x + w - 20, y + 20)
    check(got is None, f"meshbot: the pointer on the background shows no name ({got!r})")
    act(b, "['skeleton', 'cm', 'axes'].forEach((l) => soadynView.showLayer(l, true))")
    at = b.evaluate("soadynView.screenOf(2)")
    got = hover(b, at["x"], at["y"])
    check(got == "obj", f"meshbot: with every layer as opened, the pointer on body 2 shows 'obj' ({got!r})")
    # every plot axis carries a unit
    check_units(b, "meshbot", {"j1": "rad", "j4": "m"})
    clean_browser(b, page, "meshbot")
    return px


def check_units(b, name, expect):
    labels = b.evaluate("Array.from(document.querySelectorAll('.plot-axis')).map((e) => e.textContent)")
    check(labels.count("time (s)") == 2, f"{name}: both plots' time axes read 'time (s)' ({labels})")
    check(any(lbl.endswith("(J/J)") for lbl in labels), f"{name}: the energy error's axis has its unit, J/J ({labels})")
    for coord, unit in expect.items():
        b.evaluate("(() => { const s = document.getElementById('coord'); const o = Array.from(s.options).find((o) => "
                   f"o.textContent.startsWith('{coord} ')); s.value = o.value; s.dispatchEvent(new Event('change')); }})()")
        y = b.evaluate("document.querySelector('#plot-joint').parentNode.querySelector('.plot-axis-y').textContent")
        check(y == f"{coord} ({unit})", f"{name}: the joint plot of {coord} reads '{y}' (expected '{coord} ({unit})')")


def check_larger_files(b, page_dir, meshes, files, run_h5, base_px):
    """each file replaced by the same shape 1.6 times larger: its bodies cover more of the scene,
    the others about as much"""
    bigger = {"cube.stl": mf.stl_binary(mf.scaled(mf.box(), 1.6)), "pyramid_ascii.stl": mf.stl_ascii(mf.scaled(mf.pyramid(), 1.6)),
              "cube.obj": mf.obj(mf.scaled(mf.box(), 1.6)), "box.dae": mf.dae(mf.scaled(mf.box(), 1.6), rgb=(0.85, 0.1, 0.85))}
    users = {"cube.stl": ["stl_bin", "big"], "pyramid_ascii.stl": ["stl_ascii"], "cube.obj": ["obj"], "box.dae": ["dae"]}
    for name, data in bigger.items():
        with open(os.path.join(meshes, name), "wb") as f:
            f.write(data)
        page = os.path.join(page_dir, f"bigger_{name}.html")
        soadyn("view", run_h5, "-o", page, "-q")
        with open(os.path.join(meshes, name), "wb") as f:
            f.write(files[name])
        open_page(b, page)
        px = visual_pixels(b)
        grown = {n: px[n] / max(1, base_px[n]) for n in BODIES}
        others = [n for n in BODIES if n not in users[name]]
        check(all(grown[n] > 1.8 for n in users[name]) and all(0.8 < grown[n] < 1.25 for n in others),
              f"{name} 1.6 times larger: " + ", ".join(f"{n} x{grown[n]:.2f}" for n in BODIES) +
              f" (its bodies > x1.8, the others x0.8-1.25)")
        clean_browser(b, page, f"bigger {name}")


def check_broken(b, page_dir, meshes, files, run_h5):
    """files that cannot be drawn: each named in the page's note with the reason, its bodies drawn in
    their default shape (the inertia box, among the visuals), no console error; soadyn view says so
    on stderr and never waits on a FIFO"""
    nan_stl = bytearray(files["cube.stl"])
    nan_stl[84 + 12:84 + 16] = b"\x00\x00\xc0\x7f"  # the first vertex's x: NaN
    sets = {
        # refused by soadyn view (garbage, missing, a FIFO), and by the page's loader (bad XML)
        "broken": ({"cube.stl": os.urandom(1001), "pyramid_ascii.stl": None, "cube.obj": "fifo",
                    "box.dae": b'<?xml version="1.0"?><COLLADA version="1.4.1"><library_geometries><geometry'},
                   {"cube.stl": "not an STL file", "pyramid_ascii.stl": "no such file or directory",
                    "cube.obj": "not a regular file (a FIFO)", "box.dae": "the Collada loader"}),
        # a NaN in a binary STL, an ASCII STL with a facet of one vertex (the STL loader's complaint,
        # kept), an OBJ line the OBJ loader throws on, a Collada file without COLLADA
        "malformed": ({"cube.stl": bytes(nan_stl), "pyramid_ascii.stl": b"solid x\n facet normal 0 0 1\n  outer loop\n"
                       b"   vertex 0 0 0\n  endloop\n endfacet\nendsolid x\n", "cube.obj": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nq 1\n",
                       "box.dae": b'<?xml version="1.0"?><robot name="x"/>'},
                      {"cube.stl": "non-finite number", "pyramid_ascii.stl": "the STL loader: no triangles in it",
                       "cube.obj": "Unexpected line", "box.dae": "no <COLLADA> element"}),
    }
    loaders_refuse = {"broken": ["box.dae"], "malformed": ["pyramid_ascii.stl", "cube.obj"]}  # the rest: soadyn view
    for label, (changes, reasons) in sets.items():
        for name, data in changes.items():
            path = os.path.join(meshes, name)
            os.remove(path)
            if data == "fifo":
                os.mkfifo(path)
            elif data is not None:
                with open(path, "wb") as f:
                    f.write(data)
        page = os.path.join(page_dir, f"{label}.html")
        started = time.monotonic()
        p = soadyn("view", run_h5, "-o", page, "-q", timeout=60)
        took = time.monotonic() - started
        for name, data in files.items():
            path = os.path.join(meshes, name)
            if os.path.lexists(path):
                os.remove(path)
            with open(path, "wb") as f:
                f.write(data)
        notes = [line for line in p.stderr.splitlines() if line]
        refused_here = [n for n in reasons if n not in loaders_refuse[label]]
        check(all(any(n in line and reasons[n] in line for line in notes) for n in refused_here) and
              all(line.startswith("soadyn: note: ") for line in notes) and took < 30,
              f"{label}: soadyn view names each file it refused, one line each, in {took:.1f} s:\n      " + "\n      ".join(notes))
        open_page(b, page)
        counts = b.evaluate("soadynView.counts()")
        note = b.evaluate("document.getElementById('frames-note').textContent")
        for name, reason in reasons.items():
            check(any(name in e and reason in e for e in counts["meshErrors"]) and name in note and reason in note,
                  f"{label}: the page's note names {name}: {next((e for e in counts['meshErrors'] if name in e), None)!r}")
        check(sorted(counts["fellBack"]) == [0, 1, 2, 3, 4] and counts["meshes"] == 0,
              f"{label}: every body fell back to its default shape ({counts['fellBack']}), no mesh drawn")
        # the default shape is drawn among the visuals: pointing at each body finds it there
        act(b, "['skeleton', 'cm', 'axes', 'boxes'].forEach((l) => soadynView.showLayer(l, false))")
        found = [b.evaluate(f"(() => {{ const a = soadynView.screenOf({i}); return soadynView.bodyAt(a.x, a.y); }})()")
                 for i in range(len(BODIES))]
        check(found == list(range(len(BODIES))), f"{label}: each body's default shape is drawn where the body is ({found})")
        clean_browser(b, page, label)


MJCF = """<mujoco model="mjcf_meshes">
  <compiler meshdir="assets"/>
  <asset>
    <mesh name="pyr" file="pyr.stl" scale="2 2 2"/>
    <mesh name="cube" file="cube.obj" scale="0.2 0.1 0.1"/>
    <material name="paint" rgba="0.1 0.2 0.9 1"/>
  </asset>
  <worldbody>
    <body name="a" pos="0 -0.3 0"><joint name="ja" type="hinge" axis="0 0 1"/>
      <geom type="mesh" mesh="pyr" pos="0.05 0 0.02" euler="0 0 30" rgba="0.9 0.1 0.1 1" contype="0" conaffinity="0"/></body>
    <body name="b" pos="0 0.3 0"><joint name="jb" type="slide" axis="1 0 0"/>
      <geom type="mesh" mesh="cube" material="paint" contype="0" conaffinity="0"/></body>
  </worldbody>
</mujoco>
"""


def rotation(q):
    x, y, z, w = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def check_mjcf(b, tmp):
    """an MJCF model's mesh geoms: meshdir, <mesh scale>, a geom's rgba and a material's; drawn as
    MuJoCo compiled them (moved to their centre of mass, the geoms placed to match): the vertices
    land where the file and the model put them"""
    d = os.path.join(tmp, "mjcf")
    os.makedirs(os.path.join(d, "assets"))
    pyr, cube = mf.pyramid(0.1), mf.box()
    with open(os.path.join(d, "assets", "pyr.stl"), "wb") as f:
        f.write(mf.stl_binary(pyr))
    with open(os.path.join(d, "assets", "cube.obj"), "wb") as f:
        f.write(mf.obj(cube))
    with open(os.path.join(d, "model.xml"), "w") as f:
        f.write(MJCF)
    soadyn("run", os.path.join(d, "model.xml"), "-o", os.path.join(d, "run.h5"), "-q", "--t-end", "0.2")
    page = os.path.join(d, "page.html")
    soadyn("view", os.path.join(d, "run.h5"), "-o", page, "-q")
    text, data = page_data(page)
    c, s = np.cos(np.radians(30)), np.sin(np.radians(30))
    expect = {"a": np.array(pyr[0]) * 2 @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]).T + [0.05, 0, 0.02],
              "b": np.array(cube[0]) * [0.2, 0.1, 0.1]}
    for body in data["bodies"]:
        (v,) = body["visuals"]
        f = data["meshes"][v["mesh"]]
        raw = base64.b64decode(re.search(rf'id="soadyn-mesh-{v["mesh"]}">(.*?)</script>', text, re.S).group(1))
        V = np.frombuffer(raw[:12 * f["vertices"]], np.float32).reshape(-1, 3).astype(np.float64)
        placed = (V * v["size"]) @ rotation(v["q"]).T + v["p"]
        e = expect[body["name"]]
        off = max(np.abs(placed[:, None, :] - e[None, :, :]).max(axis=2).min(axis=1).max(),
                  np.abs(e[:, None, :] - placed[None, :, :]).max(axis=2).min(axis=1).max())
        check(f["format"] == "arrays" and f["error"] is None and off < 1e-5,
              f"mjcf: body {body['name']}'s mesh {f['name']} drawn where the file and the model put it (vertices {off:.1e} m off)")
    colors = {bd["name"]: bd["visuals"][0]["color"] for bd in data["bodies"]}
    check(colors == {"a": "#e51a1a", "b": "#1a33e5"}, f"mjcf: the geom's rgba and the material's ({colors})")
    open_page(b, page)
    counts = b.evaluate("soadynView.counts()")
    check(counts["meshes"] == 2 and counts["meshErrors"] == [], f"mjcf: 2 mesh geoms drawn ({counts['meshes']}, {counts['meshErrors']})")
    px = visual_pixels(b)
    check(px["stl_bin"] > 150 and px["obj"] > 150, f"mjcf: the red pyramid ({px['stl_bin']} px) and the blue box ({px['obj']} px) drawn")
    act(b, "['skeleton', 'cm', 'axes'].forEach((l) => soadynView.showLayer(l, false))")
    for i, name in enumerate(["a", "b"]):
        at = b.evaluate(f"soadynView.screenOf({i})")
        got = hover(b, at["x"], at["y"])
        check(got == name, f"mjcf: the pointer on body {name}'s mesh shows its name ({got!r})")
    check_units(b, "mjcf", {"ja": "rad", "jb": "m"})
    clean_browser(b, page, "mjcf")


def check_no_visuals(b, tmp):
    """a model without visuals is drawn in its inertia boxes; its plots carry units too"""
    h5, page = os.path.join(tmp, "dp.h5"), os.path.join(tmp, "dp.html")
    soadyn("run", os.path.join(SOURCE, "scenarios", "spherical_pendulum.yaml"), "-o", h5, "-q", "--t-end", "0.5")
    soadyn("view", h5, "-o", page, "-q")
    open_page(b, page)
    layers = b.evaluate("soadynView.layers()")
    hidden = b.evaluate("document.getElementById('show-visuals').parentNode.style.display")
    check(layers["boxes"] and hidden == "none", f"no visuals: inertia boxes shown, no visuals option ({layers}, {hidden!r})")
    coord = b.evaluate("soadynView.counts() && document.getElementById('coord').options[0].textContent")
    unit = coord.rsplit("(", 1)[-1].rstrip(")")
    check_units(b, "spherical pendulum", {coord.rsplit(" (", 1)[0]: unit})
    check(unit == "1", f"spherical pendulum: a quaternion part's unit is 1 ({coord!r})")
    clean_browser(b, page, "no visuals")


def panda(tmp, b):
    """the page of a Panda-like arm: 10 links, each drawn by a binary STL of 40 000 triangles"""
    d = os.path.join(tmp, "panda")
    os.makedirs(os.path.join(d, "meshes"))
    links = [f"link{k}" for k in range(10)]
    mesh_bytes = 0
    for k, name in enumerate(links):
        data = mf.stl_binary(mf.sphere(0.06 + 0.004 * k, 40000))
        mesh_bytes += len(data)
        with open(os.path.join(d, "meshes", name + ".stl"), "wb") as f:
            f.write(data)
    inertial = ('<inertial><origin xyz="0 0 0.05"/><mass value="2"/><inertia ixx="0.01" iyy="0.01" izz="0.004" ixy="0" ixz="0" '
                'iyz="0"/></inertial>')
    urdf = '<?xml version="1.0"?>\n<robot name="panda_like">\n'
    for name in links:
        urdf += (f'  <link name="{name}">{inertial}<visual><origin xyz="0 0 0.05"/><geometry><mesh filename="../meshes/'
                 f'{name}.stl"/></geometry></visual></link>\n')
    for k in range(1, 10):
        urdf += (f'  <joint name="joint{k}" type="revolute"><parent link="link{k - 1}"/><child link="link{k}"/>'
                 f'<origin xyz="0 0 0.1"/><axis xyz="{"0 1 0" if k % 2 else "0 0 1"}"/>'
                 '<limit lower="-2.9" upper="2.9" effort="87" velocity="2.6"/></joint>\n')
    urdf += "</robot>\n"
    os.makedirs(os.path.join(d, "urdf"))
    with open(os.path.join(d, "urdf", "panda_like.urdf"), "w") as f:
        f.write(urdf)
    soadyn("run", os.path.join(d, "urdf", "panda_like.urdf"), "-o", os.path.join(d, "run.h5"), "-q", "--t-end", "2")
    page = os.path.join(d, "panda_like.html")
    soadyn("view", os.path.join(d, "run.h5"), "-o", page, "-q", "--fps", "60")
    without = os.path.join(d, "without.html")
    shutil.move(os.path.join(d, "meshes"), os.path.join(d, "gone"))
    soadyn("view", os.path.join(d, "run.h5"), "-o", without, "-q")
    size, base = os.path.getsize(page), os.path.getsize(without)
    started = time.monotonic()
    open_page(b, page, t=1)
    took = time.monotonic() - started
    counts = b.evaluate("soadynView.counts()")
    # what pointing at a body costs (400 000 triangles), and drawing a frame in play
    pick_ms = b.evaluate("(() => { const a = soadynView.screenOf(5), t = performance.now(); const i = soadynView.bodyAt(a.x, a.y);"
                         " return [performance.now() - t, i]; })()")
    b.evaluate("soadynView.cost.render = 0; soadynView.renders = 0; soadynView.seek(0); soadynView.play()")
    b.pump(3)
    render = b.evaluate("[soadynView.cost.render, soadynView.renders]")
    per_byte = (size - base) / mesh_bytes
    print(f"panda-like arm: 10 binary STL files of 40 000 triangles, {mesh_bytes / 1e6:.2f} MB in all; page {size / 1e6:.2f} MB "
          f"({size} bytes; {base / 1e6:.2f} MB without the meshes: {per_byte:.4f} page bytes per mesh byte); "
          f"opened and drawn in {took:.1f} s in headless chromium (software WebGL); {counts['meshes']} meshes drawn; "
          f"pointing at a body: {pick_ms[0]:.0f} ms; a frame in play: {render[0] / max(1, render[1]):.0f} ms to render "
          f"({render[1]} frames in 3 s)")
    check(counts["meshes"] == 10 and counts["meshErrors"] == [] and pick_ms[1] == 5, "panda-like arm: its 10 meshes drawn, link5 picked")
    check(4 / 3 < per_byte < 4 / 3 + 0.01, f"panda-like arm: the meshes cost their base64 in the page ({per_byte:.4f} bytes per byte)")
    check(took < 60, f"panda-like arm: the {size / 1e6:.0f} MB page opens in {took:.1f} s (< 60 s)")
    clean_browser(b, page, "panda-like arm")


def main():
    if not find_chromium():
        print("chromium not found: skipped (tools/setup.sh installs it)")
        return 77
    tmp = tempfile.mkdtemp(prefix="soadyn-view-meshes-")
    try:
        urdf, meshes, files = write_meshbot(tmp)
        run_h5 = os.path.join(tmp, "meshbot.h5")
        soadyn("run", urdf, "-o", run_h5, "-q", "--t-end", "0.2")
        page = os.path.join(tmp, "meshbot.html")
        p = soadyn("view", run_h5, "-o", page)
        check(p.stderr == "", f"meshbot: soadyn view has nothing to say on stderr ({p.stderr.strip()!r})")
        check_page_data(page, p.stdout)
        with Browser() as b:
            b.open_page()
            base_px = check_good_page(b, page)
            check_larger_files(b, tmp, meshes, files, run_h5, base_px)
            check_broken(b, tmp, meshes, files, run_h5)
            check_mjcf(b, tmp)
            check_no_visuals(b, tmp)
            panda(tmp, b)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    print(f"\n{len(failures)} failure(s)" if failures else "\nall checks passed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
