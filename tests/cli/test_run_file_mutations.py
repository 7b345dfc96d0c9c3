#!/usr/bin/python3
"""Corrupt run files, deterministically: real run files (a finished double pendulum, the controlled
arm with joint limits and /events, a logged-frames scene, a killed run's SWMR file, and files of
layout 4 written by soadyn before strings became fixed-length: tests/data/run_files/) with one byte
changed at many offsets, read by the real readers as processes: `soadyn export`, `view`,
`identify --data`, a scenario's table target `{table: run.h5}` (`soadyn inspect`) and Python's
read_log.  Each must end within 10 s with exit 0 (a read: its output written) or 2 (one line naming
the file), soadyn.Error in Python — never a signal, a hang or a traceback.

Every 61st byte of the HDF5 metadata region of each layout-5 file (its first 32 KiB: superblock,
object headers, B-trees, fractal heaps) and every byte of its global heap collections' first 128,
the chunk index at the end and a few bytes among the rows go through read_log in one Python process
per file (a signal there names the offset); of a layout-4 file (each read forks a probe, ~10x the
time) every byte of its heap collections' first 64 (its strings, where libhdf5 faults) and every
331st byte of the rest.  A spread of 8 per file (half in the global heap's collections, half over
the file) goes through each command.  The counts and the time are printed at the end."""
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import unittest

SOADYN = os.environ.get("SOADYN", "build/soadyn")
ROOT = os.environ.get("SOADYN_SOURCE_DIR", os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
PYTHONPATH = os.environ.get("SOADYN_PYTHONPATH", os.path.join(os.path.dirname(os.path.abspath(SOADYN)), "python"))
SCENES = os.path.join(ROOT, "scenarios")
OLD = os.path.join(ROOT, "tests", "data", "run_files")
LIMIT = 10.0  # seconds a reader may take on any file
STRIDE = 61  # every STRIDE-th byte of a layout-5 file's metadata region goes through read_log
SPREAD = 8  # mutants of each file through each command

# one Python process reads every mutant of one file: mutate, read_log, print the outcome
READER = r"""
import sys, time, soadyn
src, out, offsets = sys.argv[1], sys.argv[2], [int(x) for x in sys.argv[3].split(",")]
data = open(src, "rb").read()
for k, off in enumerate(offsets):
    b = bytearray(data)
    b[off] ^= (0xFF, 0x01, 0x80, 0x10)[k % 4]
    with open(out, "wb") as f:
        f.write(b)
    print("reading", off, flush=True)
    t0 = time.monotonic()
    try:
        tr = soadyn.read_log(out)
        assert len(tr.q) == len(tr.t) == len(tr.v), off
        what = "read"
    except soadyn.Error as e:
        assert str(e).startswith(out + ": "), (off, str(e))
        assert "\n" not in str(e), (off, str(e))
        what = "refused"
    print("done", off, what, round(time.monotonic() - t0, 3), flush=True)
"""


def gcol_offsets(data):
    """the bytes of every global heap collection (signature GCOL; its size at +8) in the file"""
    out = []
    for m in re.finditer(b"GCOL\x01", data):
        size = int.from_bytes(data[m.start() + 8:m.start() + 16], "little")
        out.extend(range(m.start(), min(len(data), m.start() + min(size, 4096))))
    return out


class Mutations(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.mkdtemp(prefix="soadyn_mutations_")
        cls.sources = {}  # name: (path, scene its model is from)
        pend = os.path.join(SCENES, "double_pendulum.yaml")
        cls.make("pendulum", pend, "--t-end", "0.3")
        cls.make("arm_limits", os.path.join(SCENES, "arm_control_limits.yaml"), "--t-end", "0.2")
        cls.make("satellite", os.path.join(SCENES, "satellite_two_arrays.yaml"), "--t-end", "0.2")
        cls.make_killed("killed", pend)
        for name in sorted(n for n in os.listdir(OLD) if n.endswith(".h5")) if os.path.isdir(OLD) else []:
            scene = pend if "pendulum" in name else os.path.join(SCENES, "arm_control_limits.yaml")
            cls.sources["layout4_" + name[:-3]] = (os.path.join(OLD, name), scene)
        cls.stats = {"files": 0, "python": 0, "commands": 0, "refused": 0}
        cls.t0 = time.monotonic()

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.dir, ignore_errors=True)
        print(f"\n{cls.stats['files']} source files; {cls.stats['python']} mutants through read_log, "
              f"{cls.stats['commands']} command runs on mutants ({cls.stats['refused']} refused); "
              f"{time.monotonic() - cls.t0:.1f} s", file=sys.stderr)

    @classmethod
    def make(cls, name, scene, *args):
        out = os.path.join(cls.dir, name + ".h5")
        r = subprocess.run([SOADYN, "run", scene, "-o", out, "-q", *args], capture_output=True, text=True, timeout=120)
        assert r.returncode == 0, r.stderr
        cls.sources[name] = (out, scene)

    @classmethod
    def make_killed(cls, name, scene):
        """a run SIGKILLed while it writes: its file stays in SWMR-write state"""
        out = os.path.join(cls.dir, name + ".h5")
        p = subprocess.Popen([SOADYN, "run", scene, "-o", out, "-q", "--t-end", "1000", "--flush-interval", "0.02"],
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        end = time.monotonic() + 30
        while (not os.path.exists(out) or os.path.getsize(out) < 40000) and time.monotonic() < end:
            time.sleep(0.02)
        p.send_signal(signal.SIGKILL)
        p.wait()
        assert os.path.exists(out)
        cls.sources[name] = (out, scene)

    def offsets_all(self, data, old):
        """the metadata (superblock, object headers, B-trees, fractal heaps: the first 32 KiB) every
        STRIDE-th byte, every byte of each global heap collection's header and first objects, the
        chunk index at the end, and the rows' bytes (raw numbers) sparsely; a layout-4 file (each
        read forks a probe) its heap densely and the rest, the same format as layout 5's, sparsely"""
        size, heap = len(data), set()
        for m in re.finditer(b"GCOL\x01", data):
            heap |= set(range(m.start(), min(size, m.start() + (64 if old else 128))))
        stride, tail = (331, 32) if old else (STRIDE, 8)
        return sorted(set(range(8, min(size, 32768), stride)) | heap | set(range(max(8, size - 512), size, tail)) |
                      set(range(32768, size, 4099)))

    def offsets_spread(self, data, n=SPREAD):
        heap = gcol_offsets(data)
        picked = [heap[k * len(heap) // (n // 2)] for k in range(n // 2)] if heap else []
        rest = n - len(picked)
        picked += [8 + k * (len(data) - 9) // rest for k in range(rest)]
        return sorted(set(picked))

    def check_line(self, r, what, names):
        lines = [line for line in r.stderr.splitlines() if line.strip()]
        self.assertEqual(len(lines), 1, (what, r.stderr))
        self.assertTrue(any(n in lines[0] for n in names), (what, lines[0]))
        self.assertNotIn("Traceback", r.stderr)

    def test_read_log_on_every_mutant(self):
        env = dict(os.environ, PYTHONPATH=PYTHONPATH)
        jobs = []
        for name, (src, _) in sorted(self.sources.items()):
            self.stats["files"] += 1
            with open(src, "rb") as f:
                offsets = self.offsets_all(f.read(), name.startswith("layout4_"))
            out = os.path.join(self.dir, f"py_{name}.h5")
            jobs.append((name, offsets, [sys.executable, "-c", READER, src, out, ",".join(map(str, offsets))]))
        # two readers at a time (the CI's two cores); each with its own mutant file
        running, t0 = [], time.monotonic()
        while jobs or running:
            while jobs and len(running) < 2:
                name, offsets, cmd = jobs.pop(0)
                running.append((name, offsets, subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                                                text=True, env=env)))
            name, offsets, p = running.pop(0)
            stdout, stderr = p.communicate(timeout=300)
            lines = stdout.splitlines()
            last = next((line for line in reversed(lines) if line.startswith("reading")), "")
            self.assertEqual(p.returncode, 0, f"{name}: read_log died at {last} ({p.returncode}): {stderr[-2000:]}")
            done = [line.split() for line in lines if line.startswith("done")]
            self.assertEqual(len(done), len(offsets), name)
            slow = [d for d in done if float(d[3]) >= LIMIT]
            self.assertEqual(slow, [], f"{name}: reads of {LIMIT} s or more")
            self.assertEqual(stderr.strip(), "", f"{name}: nothing on stderr (a probe's child says nothing)")
            self.stats["python"] += len(done)
            self.stats["refused"] += sum(d[2] == "refused" for d in done)
            print(f"{name}: {len(done)} mutants ({sum(d[2] == 'refused' for d in done)} refused), "
                  f"slowest {max(float(d[3]) for d in done):.2f} s; {time.monotonic() - t0:.1f} s", file=sys.stderr)

    def test_commands_on_a_spread_of_mutants(self):
        for name, (src, scene) in sorted(self.sources.items()):
            with open(src, "rb") as f:
                data = f.read()
            for k, off in enumerate(self.offsets_spread(data)):
                b = bytearray(data)
                b[off] ^= (0xFF, 0x01, 0x80, 0x10)[k % 4]
                m = os.path.join(self.dir, "m.h5")
                with open(m, "wb") as f:
                    f.write(b)
                table = os.path.join(self.dir, "table.yaml")
                with open(scene) as f:
                    text = f.read()
                if "double_pendulum" in scene:  # a PD target read from the mutant (its /q by joint name)
                    text = text.replace("simulation:", "inputs:\n  controllers:\n    - {type: pd, joint: theta1, kp: 1, "
                                        "kd: 0.1, target: {table: m.h5}}\nsimulation:")
                with open(table, "w") as f:
                    f.write(text)
                cmds = [("export", [SOADYN, "export", m, "--csv", os.path.join(self.dir, "x.csv"), "-q", "--force"]),
                        ("view", [SOADYN, "view", m, "-o", os.path.join(self.dir, "x.html"), "-q", "--force"])]
                if "double_pendulum" in scene:
                    cmds += [("identify", [SOADYN, "identify", scene, "--data", m, "--parameters", "lower"]),
                             ("table", [SOADYN, "inspect", table])]
                for what, cmd in cmds:
                    t0 = time.monotonic()
                    r = subprocess.run(cmd, capture_output=True, text=True, timeout=LIMIT * 3)
                    took = time.monotonic() - t0
                    self.stats["commands"] += 1
                    where = f"{name} byte {off}: {what}"
                    self.assertLess(took, LIMIT, where)
                    self.assertIn(r.returncode, (0, 2), f"{where}: exit {r.returncode}: {r.stderr}")
                    if r.returncode == 2:
                        self.stats["refused"] += 1
                        self.check_line(r, where, (m, "m.h5", scene, "identify: "))
                    elif what in ("export", "view"):
                        out = cmd[4]
                        self.assertGreater(os.path.getsize(out), 0, where)


if __name__ == "__main__":
    unittest.main(verbosity=2)
