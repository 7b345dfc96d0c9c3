#!/usr/bin/python3
"""Playback benchmark of `soadyn view` pages in headless chromium (a benchmark, not a test).

Simulates the 64-link chain of the benchmarks (tools/bench/make_models.py) for 10 000 logged
frames, writes its page, plays it at x1 and counts, with requestAnimationFrame, the frames the
browser shows and the frames the page draws, after a 2 s warm-up, over three windows of wall time
(the median is reported, with the load average: chromium renders WebGL in software here, so a
loaded machine lowers the rate).  Goal: >= 30 fps.

  tools/view_bench.py [--bodies 64] [--frames 10000] [--seconds 5] [--repeat 3] [--size 1280x720] [--json FILE]

SOADYN names the executable (default build/soadyn).
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
sys.path.insert(0, os.path.join(ROOT, "tools", "view"))
sys.path.insert(0, os.path.join(ROOT, "tools", "bench"))
from cdp import Browser  # noqa: E402
from make_models import urdf  # noqa: E402

MEASURE = """
new Promise((done) => {
  const v = window.soadynView;
  if (!v.state().playing) { v.seek(0); v.setSpeed(1); v.play(); }
  let r0, t0, c0;
  let raf = 0, start = null, worst = 0, last = null;
  function tick(now) {
    if (start === null) { start = now; last = now; r0 = v.renders; t0 = v.state().t; c0 = Object.assign({}, v.cost); }
    raf += 1; worst = Math.max(worst, now - last); last = now;
    if (now - start < %(ms)f) requestAnimationFrame(tick);
    else done({ seconds: (now - start) / 1000, raf_frames: raf - 1, page_renders: v.renders - r0,
                sim_seconds: v.state().t - t0, worst_frame_ms: worst,
                ms_per_render: Object.fromEntries(Object.keys(c0).map((k) => [k, (v.cost[k] - c0[k]) / Math.max(1, v.renders - r0)])) });
  }
  requestAnimationFrame(tick);
})
"""


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bodies", type=int, default=64)
    ap.add_argument("--frames", type=int, default=10000)
    ap.add_argument("--seconds", type=float, default=5.0, help="length of one measured window")
    ap.add_argument("--repeat", type=int, default=3, help="windows measured (the median is reported)")
    ap.add_argument("--size", default="1280x720")
    ap.add_argument("--json", help="also write the result here")
    a = ap.parse_args()
    soadyn = os.environ.get("SOADYN", os.path.join(ROOT, "build", "soadyn"))
    width, height = (int(x) for x in a.size.split("x"))
    with tempfile.TemporaryDirectory(prefix="soadyn-view-bench-") as tmp:
        model = os.path.join(tmp, f"chain_{a.bodies}.urdf")
        with open(model, "w") as f:
            f.write(urdf(a.bodies, False))
        dt_out = 0.02
        h5, page = os.path.join(tmp, "chain.h5"), os.path.join(tmp, "chain.html")
        t = time.time()
        subprocess.run([soadyn, "run", model, "-q", "-o", h5, "--method", "rk4", "--dt", "0.002", "--output-dt",
                        str(dt_out), "--t-end", str(dt_out * (a.frames - 1))], check=True)
        t_run = time.time() - t
        t = time.time()
        out = subprocess.run([soadyn, "view", h5, "-o", page, "--max-frames", str(a.frames)], check=True,
                             capture_output=True, text=True).stdout
        t_view = time.time() - t
        print(out, end="")
        with Browser(width, height) as b:
            b.open_page()
            t = time.time()
            b.navigate("file://" + page + "#t=0")
            b.wait_for("window.soadynView && soadynView.ready && soadynView.renders > 0", timeout=300)
            t_load = time.time() - t
            st = b.evaluate("soadynView.state()")
            b.evaluate(MEASURE % {"ms": 2000}, timeout=120, await_promise=True)  # warm-up
            runs = [b.evaluate(MEASURE % {"ms": 1000 * a.seconds}, timeout=a.seconds + 120, await_promise=True)
                    for _ in range(a.repeat)]
            errors = b.console_errors()
            with open("/proc/loadavg") as f:
                load = float(f.read().split()[0])
        runs.sort(key=lambda r: r["page_renders"] / r["seconds"])
        r = runs[len(runs) // 2]  # the median window
        result = {
            "bodies": st["bodies"], "frames": st["frames"], "viewport": a.size,
            "page_mb": round(os.path.getsize(page) / 1e6, 2), "run_s": round(t_run, 2), "view_s": round(t_view, 2),
            "load_s": round(t_load, 2), "measured_s": round(r["seconds"], 2),
            "browser_fps": round(r["raf_frames"] / r["seconds"], 1),
            "page_fps": round(r["page_renders"] / r["seconds"], 1),
            "page_fps_windows": [round(x["page_renders"] / x["seconds"], 1) for x in runs],
            "load_average": load, "cores": os.cpu_count(),
            "playback_rate": round(r["sim_seconds"] / r["seconds"], 3),
            "worst_frame_ms": round(r["worst_frame_ms"], 1),
            "ms_per_frame": {k: round(v, 2) for k, v in r["ms_per_render"].items()}, "console_errors": errors,
        }
    print(json.dumps(result, indent=1))
    ok = result["page_fps"] >= 30 and not errors
    print(f"{'PASS' if ok else 'FAIL'}: {result['page_fps']} frames drawn per second "
          f"({result['bodies']} bodies, {result['frames']} frames, load average {load} on {os.cpu_count()} cores; goal >= 30)")
    if a.json:
        with open(a.json, "w") as f:
            json.dump(result, f, indent=1)
            f.write("\n")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
