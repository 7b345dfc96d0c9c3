#!/usr/bin/python3
"""Never destroy what isn't the run's: every writer (run, view, export) replaces only what it made
(or with --force), never an input under any name, never a file another writer holds, never a device
or FIFO; readers end at once on corrupt files, FIFOs, devices and oversized inputs.  Real
processes, real files, real FIFOs and device nodes (made with mknod in a temporary folder, so the
machine's /dev is never at stake)."""
import glob
import hashlib
import os
import random
import resource
import shutil
import signal
import stat
import subprocess
import sys
import tempfile
import threading
import time
import unittest

import h5py
import numpy as np

SOADYN = os.environ.get("SOADYN", "build/soadyn")
ROOT = os.environ.get("SOADYN_SOURCE_DIR", os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
PENDULUM = os.path.join(ROOT, "scenarios", "double_pendulum.yaml")
ARM_URDF = os.path.join(ROOT, "scenarios", "two_link_arm.urdf")
PYTHONPATH = os.environ.get("SOADYN_PYTHONPATH", os.path.join(os.path.dirname(os.path.abspath(SOADYN)), "python"))


def run(*args, timeout=60, **kw):
    return subprocess.run([SOADYN, *args], capture_output=True, text=True, timeout=timeout, **kw)


def digest(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


class Base(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="soadyn_outputs_")

    def tearDown(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def path(self, name):
        return os.path.join(self.dir, name)

    def make_run(self, name="r.h5", *extra):
        out = self.path(name)
        r = run("run", PENDULUM, "-o", out, "-q", *(extra or ("--t-end", "1")))
        self.assertEqual(r.returncode, 0, r.stderr)
        return out

    def assertRefused(self, r, pattern, code=2):
        self.assertEqual(r.returncode, code, r.stdout + r.stderr)
        lines = [line for line in r.stderr.splitlines() if line.strip()]
        self.assertEqual(len(lines), 1, r.stderr)
        self.assertRegex(lines[0], pattern)
        self.assertNotIn("Traceback", r.stderr)

    def assertNoLitter(self):
        left = [p for p in os.listdir(self.dir) if p.endswith(".tmp") or p.endswith(".lock")]
        self.assertEqual(left, [], "no temporary or lock file left")


class ViewOutput(Base):
    def test_view_onto_its_own_run_under_any_name_is_refused(self):
        r_h5 = self.make_run()
        os.symlink(r_h5, self.path("link.h5"))
        os.link(r_h5, self.path("hard.h5"))
        before = digest(r_h5)
        for out in (r_h5, self.path("link.h5"), self.path("hard.h5")):
            self.assertRefused(run("view", r_h5, "-o", out, "-q"), r"the output is the input file")
            self.assertEqual(digest(r_h5), before)
        self.assertNoLitter()

    def test_view_onto_another_run_file_is_refused(self):
        a, b = self.make_run("a.h5"), self.make_run("b.h5")
        before = digest(b)
        self.assertRefused(run("view", a, "-o", b, "-q"), r"b\.h5: exists and is an HDF5 file \(a run\?\), not a soadyn page.*--force")
        self.assertEqual(digest(b), before)

    def test_view_onto_a_running_run_is_refused(self):
        a = self.make_run("a.h5")
        out = self.path("running.h5")
        p = subprocess.Popen([SOADYN, "run", PENDULUM, "-o", out, "-q", "--method", "rk4", "--dt", "1e-6",
                              "--t-end", "100", "--output-dt", "1"], stderr=subprocess.PIPE, text=True)
        try:
            end = time.monotonic() + 30
            while not os.path.exists(out + ".lock") and time.monotonic() < end:
                time.sleep(0.01)
            for force in ([], ["--force"]):
                self.assertRefused(run("view", a, "-o", out, "-q", *force), r"in use by another soadyn run \(pid \d+\)")
                self.assertRefused(run("export", a, "--csv", out, *force), r"in use by another soadyn run")
            self.assertIsNone(p.poll(), "the run goes on")
        finally:
            p.send_signal(signal.SIGINT)
            p.wait(timeout=60)

    def test_view_replaces_its_own_page_and_a_foreign_file_only_with_force(self):
        r_h5 = self.make_run()
        page = self.path("r.html")
        self.assertEqual(run("view", r_h5, "-q", "-o", page).returncode, 0)
        self.assertEqual(run("view", r_h5, "-q", "-o", page).returncode, 0, "its own page is replaced")
        notes = self.path("notes.html")
        with open(notes, "w") as f:
            f.write("<!DOCTYPE html><html><body>my notes</body></html>\n")
        self.assertRefused(run("view", r_h5, "-q", "-o", notes), r"not a soadyn page")
        with open(notes) as f:
            self.assertIn("my notes", f.read())
        self.assertEqual(run("view", r_h5, "-q", "-o", notes, "--force").returncode, 0)
        with open(notes) as f:
            self.assertIn('content="soadyn view"', f.read())
        self.assertNoLitter()


class RunOutput(Base):
    def test_a_foreign_hdf5_file_is_replaced_only_with_force(self):
        precious = self.path("precious.h5")
        with h5py.File(precious, "w") as f:
            f["weights"] = np.arange(10.0)
        before = digest(precious)
        self.assertRefused(run("run", PENDULUM, "-o", precious, "-q", "--t-end", "0.1"),
                           r"precious\.h5: exists and is an HDF5 file but not a soadyn run file.*--force")
        self.assertEqual(digest(precious), before)
        r = run("run", PENDULUM, "-o", precious, "-q", "--t-end", "0.1", "--force")
        self.assertEqual(r.returncode, 0, r.stderr)
        with h5py.File(precious, "r") as f:
            self.assertIn("soadyn_version", f.attrs)
        self.assertNoLitter()

    def test_a_soadyn_run_file_is_replaced(self):
        out = self.make_run()
        self.make_run()
        with h5py.File(out, "r") as f:
            self.assertIn("soadyn_version", f.attrs)

    def test_a_file_open_for_writing_elsewhere_is_refused_even_with_force(self):
        out = self.path("open.h5")
        holder = subprocess.Popen([sys.executable, "-c", (
            "import h5py, sys, time\n"
            f"f = h5py.File({out!r}, 'w')\n"
            "f['x'] = [1.0]\nf.flush()\nprint('open', flush=True)\ntime.sleep(60)\n")],
            stdout=subprocess.PIPE, text=True)
        try:
            self.assertEqual(holder.stdout.readline().strip(), "open")
            for force in ([], ["--force"]):
                self.assertRefused(run("run", PENDULUM, "-o", out, "-q", "--t-end", "0.1", *force),
                                   r"open for writing by another program")
        finally:
            holder.kill()
            holder.wait()

    def test_a_device_or_fifo_is_not_a_run_file(self):
        fifo = self.path("fifo")
        os.mkfifo(fifo)
        self.assertRefused(run("run", PENDULUM, "-o", fifo, "-q", "--force", timeout=10), r"not a regular file")
        self.assertTrue(stat.S_ISFIFO(os.stat(fifo).st_mode))

    def test_a_file_size_limit_is_a_write_error_not_a_silent_death(self):
        out = self.path("big.h5")
        limit = 64 * 1024

        def cap():
            resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

        r = subprocess.run([SOADYN, "run", PENDULUM, "-o", out, "-q", "--method", "rk4", "--dt", "1e-4",
                            "--t-end", "20", "--output-dt", "1e-4", "--flush-interval", "0.01"],
                           capture_output=True, text=True, timeout=120, preexec_fn=cap)
        self.assertEqual(r.returncode, 4, r.stderr)
        self.assertRegex(r.stderr, r"(?i)file too large")
        self.assertEqual(glob.glob(out + ".lock"), [], "the lock is released")


class ExportOutput(Base):
    def test_export_never_replaces_the_scenario_or_other_text(self):
        r_h5 = self.make_run()
        scenario = self.path("dp.yaml")
        shutil.copy(PENDULUM, scenario)
        before = digest(scenario)
        self.assertRefused(run("export", r_h5, "--csv", scenario), r"dp\.yaml: exists and is not a soadyn CSV export")
        self.assertRefused(run("export", r_h5, "--json", scenario), r"not a soadyn JSON export")
        self.assertEqual(digest(scenario), before)
        # its own exports are replaced; another text file only with --force
        csv, js = self.path("x.csv"), self.path("x.json")
        for _ in range(2):
            r = run("export", r_h5, "--csv", csv, "--json", js, "-q")
            self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(run("export", r_h5, "--csv", scenario, "--force", "-q").returncode, 0)
        self.assertTrue(open(scenario).read().startswith("time [s]"))
        self.assertNoLitter()

    def test_the_same_file_for_csv_and_json_is_one_clear_line(self):
        r_h5 = self.make_run()
        x = self.path("x")
        self.assertRefused(run("export", r_h5, "--csv", x, "--json", x), r"named for two outputs")
        self.assertFalse(os.path.exists(x))

    def test_devices_are_written_in_place_never_replaced(self):
        if os.geteuid() != 0:
            self.skipTest("mknod needs root")
        r_h5 = self.make_run()
        null, full = self.path("null"), self.path("full")
        os.mknod(null, 0o666 | stat.S_IFCHR, os.makedev(1, 3))
        os.mknod(full, 0o666 | stat.S_IFCHR, os.makedev(1, 7))
        r = run("export", r_h5, "--csv", null, "-q")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertTrue(stat.S_ISCHR(os.stat(null).st_mode), "still a device")
        self.assertEqual(os.stat(null).st_rdev, os.makedev(1, 3))
        r = run("export", r_h5, "--json", full, "-q")
        self.assertEqual(r.returncode, 4, r.stderr)
        self.assertRegex(r.stderr, r"(?i)no space left on device")
        self.assertTrue(stat.S_ISCHR(os.stat(full).st_mode))
        self.assertEqual(run("view", r_h5, "-o", null, "-q").returncode, 0)
        self.assertTrue(stat.S_ISCHR(os.stat(null).st_mode))
        self.assertNoLitter()

    def test_stdout_is_written_in_place(self):
        r_h5 = self.make_run()
        r = run("export", r_h5, "--csv", "-", "--columns", "time")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(r.stdout.splitlines()[0], "time [s]")
        r = subprocess.run(f"{SOADYN} export {r_h5} --csv /dev/stdout --columns time | head -1",
                           shell=True, capture_output=True, text=True, timeout=30)
        self.assertEqual(r.stdout.strip(), "time [s]")
        self.assertTrue(stat.S_ISCHR(os.stat("/dev/null").st_mode))

    def test_a_fifo_is_written_in_place_and_one_without_reader_is_refused(self):
        r_h5 = self.make_run()
        fifo = self.path("fifo")
        os.mkfifo(fifo)
        t0 = time.monotonic()
        self.assertRefused(run("export", r_h5, "--csv", fifo, timeout=10), r"a FIFO with no reader")
        self.assertLess(time.monotonic() - t0, 10)
        got = []
        reader = threading.Thread(target=lambda: got.append(open(fifo).read()))
        reader.start()
        time.sleep(0.2)
        r = run("export", r_h5, "--csv", fifo, "-q", timeout=30)
        reader.join(timeout=30)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertTrue(got and got[0].startswith("time [s]"))
        self.assertTrue(stat.S_ISFIFO(os.stat(fifo).st_mode))

    def test_a_killed_export_leaves_no_temporary_file(self):
        # rows enough that the export is still writing when the signal comes: a json output into
        # a FIFO nobody reads holds it mid-file, its CSV under the temporary name
        r_h5 = self.make_run("long.h5", "--t-end", "20", "--output-dt", "1e-3")
        csv, fifo = self.path("x.csv"), self.path("stall")
        os.mkfifo(fifo)
        keep = os.open(fifo, os.O_RDONLY | os.O_NONBLOCK)  # a reader that never reads
        try:
            for sig in (signal.SIGTERM, signal.SIGKILL):
                p = subprocess.Popen([SOADYN, "export", r_h5, "--csv", csv, "--json", fifo],
                                     stderr=subprocess.PIPE, text=True)
                end = time.monotonic() + 30
                while not glob.glob(csv + ".*.tmp") and time.monotonic() < end:
                    time.sleep(0.01)
                self.assertTrue(glob.glob(csv + ".*.tmp"), "the export is under way")
                time.sleep(0.2)
                p.send_signal(sig)
                p.wait(timeout=30)
                self.assertEqual(p.returncode, 128 + sig if sig == signal.SIGTERM else -sig)
                if sig == signal.SIGTERM:
                    self.assertEqual(glob.glob(csv + ".*"), [], "SIGTERM removes the temporary file and the lock")
                while True:  # empty the FIFO for the next round
                    try:
                        if not os.read(keep, 1 << 16):
                            break
                    except BlockingIOError:
                        break
            self.assertTrue(glob.glob(csv + ".*.tmp"), "SIGKILL leaves it ...")
            self.assertFalse(os.path.exists(csv))
            r = run("export", r_h5, "--csv", csv, "-q", "--columns", "time")
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertEqual(glob.glob(csv + ".*"), [], "... and the next export to that path removes it")
        finally:
            os.close(keep)


class CorruptFiles(Base):
    def corrupt_copies(self, source, count, seed):
        rng = random.Random(seed)
        size = os.path.getsize(source)
        with open(source, "rb") as f:
            data = f.read()
        out = []
        for k in range(count):
            b = bytearray(data)
            for _ in range(50):
                b[rng.randrange(8, size)] = rng.randrange(256)
            p = self.path(f"c{seed}_{k}.h5")
            with open(p, "wb") as f:
                f.write(b)
            out.append(p)
        return out

    def test_corrupt_run_files_end_within_ten_seconds(self):
        src = self.make_run()
        env = dict(os.environ, PYTHONPATH=PYTHONPATH)
        reader = "import sys, soadyn\ntry:\n    soadyn.read_log(sys.argv[1])\nexcept soadyn.Error as e:\n    print(e, file=sys.stderr); sys.exit(2)\n"
        for seed in (1, 2, 3):
            for c in self.corrupt_copies(src, 5, seed):
                for cmd in ([SOADYN, "export", c, "--csv", self.path("x.csv"), "-q"],
                            [SOADYN, "view", c, "-o", self.path("x.html"), "-q"],
                            [sys.executable, "-c", reader, c]):
                    t0 = time.monotonic()
                    r = subprocess.run(cmd, capture_output=True, text=True, timeout=20, env=env)
                    self.assertLess(time.monotonic() - t0, 10, cmd)
                    self.assertIn(r.returncode, (0, 2), (cmd, r.stderr))
                    self.assertNotIn("Traceback", r.stderr)
                    if r.returncode:
                        self.assertEqual(len(r.stderr.strip().splitlines()), 1, r.stderr)
        self.assertNoLitter()


class Inputs(Base):
    def test_fifos_and_devices_as_inputs_are_refused_at_once(self):
        fifo = self.path("robot.urdf")
        os.mkfifo(fifo)
        yaml_fifo = self.path("scene.yaml")
        os.mkfifo(yaml_fifo)
        scene = self.path("uses_fifo.yaml")
        with open(scene, "w") as f:
            f.write("urdf: robot.urdf\n")
        for args in (["inspect", fifo], ["inspect", yaml_fifo], ["run", yaml_fifo, "-o", self.path("o.h5")],
                     ["inspect", scene], ["inspect", "/dev/zero"], ["run", "/dev/zero", "-o", self.path("o.h5")]):
            t0 = time.monotonic()
            r = run(*args, timeout=10)
            self.assertLess(time.monotonic() - t0, 10)
            self.assertRefused(r, r"not a regular file")
        self.assertFalse(os.path.exists(self.path("o.h5")))

    def test_an_oversized_input_is_refused_before_it_is_read(self):
        big = self.path("huge.yaml")
        with open(big, "wb") as f:
            f.truncate(65 << 20)  # sparse: no disk, 65 MiB of NULs
        self.assertRefused(run("inspect", big), r"huge\.yaml: 65 MiB, more than the 64 MiB")


class Scenarios(Base):
    def scene(self, text, name="s.yaml"):
        p = self.path(name)
        with open(p, "w") as f:
            f.write(text)
        return p

    BASE = ("bodies:\n  - name: link\n    joint: {type: revolute, name: hinge, axis: [0, 0, 1]}\n"
            "    mass: 1.0\n    com: [0.5, 0, 0]\n    inertia: [0.1, 0.1, 0.1]\n")

    def test_a_huge_initial_angle_is_refused_naming_the_field(self):
        r = run("inspect", PENDULUM, "--q", "0,1e300")
        self.assertRefused(r, r"--q: theta2 = 1e\+300: expected \|value\| <= 1e\+06")
        with open(PENDULUM) as f:
            text = f.read().replace("theta2: -0.5}", "theta2: 1.0e300}")
        self.assertIn("1.0e300", text)
        t0 = time.monotonic()
        r = run("run", self.scene(text), "-o", self.path("o.h5"), timeout=20)
        self.assertLess(time.monotonic() - t0, 10)
        self.assertRefused(r, r"s\.yaml:20:.*initial\.q\.theta2.*expected \|value\| <= 1e\+06")
        self.assertFalse(os.path.exists(self.path("o.h5")))

    def test_a_second_yaml_document_is_refused(self):
        p = self.scene(self.BASE + "---\nname: other\n")
        self.assertRefused(run("inspect", p), r"s\.yaml:\d+:.*second document")

    def test_a_string_where_a_number_is_expected(self):
        p = self.scene(self.BASE.replace("mass: 1.0", "mass: !!str 1.0"))
        self.assertRefused(run("inspect", p), r"s\.yaml:\d+:.*mass.*expected a number, got the string '1.0'")
        p = self.scene(self.BASE.replace("mass: 1.0", 'mass: "1.0"'))
        self.assertRefused(run("inspect", p), r"expected a number, got the string")

    def test_a_step_longer_than_the_run_is_said(self):
        out = self.path("o.h5")
        r = run("run", PENDULUM, "-o", out, "--method", "rk4", "--dt", "0.5", "--t-end", "0.2", "--output-dt", "0.1")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("warning: dt 0.5 is longer than t_end 0.2: the run is one step of 0.2", r.stderr)
        with h5py.File(out, "r") as f:
            self.assertEqual(len(f["time"]), 2)  # t = 0 and the one step's end
            self.assertLess(abs(f["time"][-1] - 0.2), 1e-15)
        r = run("run", PENDULUM, "-o", out, "--method", "rk4", "--dt", "0.01", "--t-end", "0.2", "--output-dt", "0.001")
        self.assertIn("warning: dt 0.01 is longer than output_dt 0.001: a sample after every step", r.stderr)
        r = run("run", PENDULUM, "-o", out, "--t-end", "0.2", "--output-dt", "0.5")
        self.assertIn("warning: output_dt 0.5 is longer than t_end 0.2", r.stderr)
        # a run as written says nothing
        r = run("run", PENDULUM, "-o", out, "--method", "rk4", "--dt", "0.01", "--t-end", "0.2", "--output-dt", "0.05")
        self.assertEqual((r.returncode, r.stderr.count("warning")), (0, 0), r.stderr)

    def chain(self, n):
        body = ("  - name: b{i}\n    parent: b{p}\n    origin: {{xyz: [0, 0, -0.1]}}\n"
                "    joint: {{type: revolute, name: j{i}, axis: [1, 0, 0]}}\n"
                "    mass: 0.1\n    com: [0, 0, -0.05]\n    inertia: [0.001, 0.001, 0.0001]\n")
        text = "bodies:\n" + "".join(body.format(i=i, p=i - 1) for i in range(n)).replace("    parent: b-1\n", "", 1)
        return self.scene(text + "simulation: {t_end: 0.001, output_dt: 0.001}\n", f"chain{n}.yaml")

    def test_memory_is_linear_but_for_the_mass_matrix_and_too_much_is_refused_early(self):
        # under ulimit -v 1 GB: a 4000-link chain runs (its 3 nv×nv matrices are 0.38 GB; the run
        # once held ten, 1.2 GB); a Newton method's workspace, 3.5 GB, is refused before it exists
        one_gb = lambda: resource.setrlimit(resource.RLIMIT_AS, (10 ** 9, resource.RLIM_INFINITY))
        p = self.chain(4000)
        r = run("run", p, "-o", self.path("c.h5"), "-q", preexec_fn=one_gb)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertRefused(run("run", p, "-o", self.path("b.h5"), "--method", "cvode-bdf", preexec_fn=one_gb),
                           r"chain4000\.yaml: the model has nv = 4000: the nv×nv matrices of a cvode-bdf run need "
                           r"about 3\.5 GB, more than the 1\.0 GB this process may use")
        self.assertFalse(os.path.exists(self.path("b.h5")))
        # 20 000 links: 9.6 GB for 𝓜 alone, said at once by run and inspect (it was std::bad_alloc)
        p = self.chain(20000)
        # (before any nv×nv work: the refusal's CPU time, which a loaded machine does not stretch as it
        # does the wall time, stays under 10 s)
        for cmd in (["run", p, "-o", self.path("d.h5")], ["inspect", p]):
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            self.assertRefused(run(*cmd, preexec_fn=one_gb, timeout=60), r"nv = 20000: .* need about 9\.6 GB")
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            self.assertLess(after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime, 10)
        self.assertNoLitter()

    def test_control_characters_from_a_file_are_not_printed_raw(self):
        r_h5 = self.make_run()
        with h5py.File(r_h5, "r+") as f:
            del f["solver/status"]
            # fixed-length, as layout 5 writes every string (a variable-length one is refused as crafted)
            f["solver/status"] = np.bytes_("completed\x1b[2J\x1b]0;owned\x07")
        r = run("view", r_h5, "-o", self.path("v.html"))
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertNotIn("\x1b", r.stdout)
        self.assertNotIn("\x07", r.stdout)
        self.assertIn("completed", r.stdout)


if __name__ == "__main__":
    unittest.main(verbosity=2)
