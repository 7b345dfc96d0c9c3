#!/usr/bin/python3
"""The READMEs' shell commands run verbatim, in order, and none overwrites another's output.

Which READMEs: README.md, then the folder READMEs (READMES below), each written to be run from the
top of a clone.  Which commands: every line of every ```sh block (a line ending in a backslash joins
the next; blank and comment-only lines are not commands), and every ```python block as one command
(/usr/bin/python3 reading it), in their order in the file — but for README.md's and
src/python/README.md's Python examples, which tests/python/test_readme.py runs with its own checks —
except
  - the two set-up commands, tools/demo.sh and tools/test.sh (the test runs after them), and
  - blocks preceded by the line `<!-- README test: not run (reason) -->` (network, installing).
Where: one scratch directory holding links to the source tree's scenarios/, tests/ and tools/ and a
build/ whose soadyn is the executable under test (SOADYN), so README's relative paths resolve and
every output lands in the scratch directory.  Each command must exit 0, and must not modify a
file that an earlier command wrote, nor anything in the source tree (git status, when it is a
git work tree).

    test_readme_commands.py [--list]      --list: print the commands and the skipped ones
"""
import os
import re
import subprocess
import sys
import tempfile
import time

ROOT = os.environ.get("SOADYN_SOURCE_DIR", os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SOADYN = os.environ.get("SOADYN", os.path.join(ROOT, "build", "soadyn"))
SETUP = ("tools/demo.sh", "tools/test.sh")
READMES = ("README.md", "src/cli/README.md", "scenarios/README.md", "include/soadyn/README.md",
           "src/python/README.md", "tools/results/README.md", "tests/README.md")
PYTHON_ELSEWHERE = ("README.md", "src/python/README.md")  # their ```python blocks: tests/python/test_readme.py
SKIP = re.compile(r"<!--\s*README test: not run \((.+?)\)\s*-->")


def commands(readme):
    """[("file:line", command)] to run, and [("file:line", command, reason)] skipped, of one README"""
    name = readme
    lines = open(os.path.join(ROOT, readme), encoding="utf-8").read().split("\n")
    run, skipped = [], []
    k = 0
    while k < len(lines):
        if lines[k].strip() == "```python" and readme not in PYTHON_ELSEWHERE:
            end = lines.index("```", k + 1)
            block = "\n".join(lines[k + 1:end])
            run.append((f"{name}:{k + 2}", f"/usr/bin/python3 - <<'PYTHON'\n{block}\nPYTHON"))
            k = end + 1
            continue
        if lines[k].strip() != "```sh":
            k += 1
            continue
        reason = None
        for j in range(k - 1, -1, -1):  # the nearest non-blank line above the fence
            if lines[j].strip():
                m = SKIP.search(lines[j])
                reason = m.group(1) if m else None
                break
        k += 1
        pending, start = "", None
        while k < len(lines) and lines[k].strip() != "```":
            line = lines[k]
            if pending or (line.strip() and not line.lstrip().startswith("#")):
                start = start or k + 1
                if line.rstrip().endswith("\\"):
                    pending += line.rstrip()[:-1] + " "
                else:
                    cmd = pending + line
                    pending = ""
                    where = f"{name}:{start}"
                    if reason:
                        skipped.append((where, cmd.strip(), reason))
                    elif cmd.strip().startswith(SETUP):
                        skipped.append((where, cmd.strip(), "set-up: runs before this test"))
                    else:
                        run.append((where, cmd.strip()))
                    start = None
            k += 1
        k += 1
    return run, skipped


def snapshot(d):
    """{path: (inode, size, mtime)} of every file under d, links not followed"""
    out = {}
    for dirpath, dirnames, files in os.walk(d):
        for name in files:
            p = os.path.join(dirpath, name)
            st = os.lstat(p)
            out[os.path.relpath(p, d)] = (st.st_ino, st.st_size, st.st_mtime_ns)
    return out


def git_status():
    p = subprocess.run(["git", "-C", ROOT, "status", "--porcelain", "--untracked-files=all", "--", "scenarios", "tests",
                        "tools", "src", "include", "README.md"], capture_output=True, text=True)
    return p.stdout if p.returncode == 0 else None


def main():
    run, skipped = [], []
    for readme in READMES:
        if os.path.exists(os.path.join(ROOT, readme)):
            r, k = commands(readme)
            run += r
            skipped += k
    if "--list" in sys.argv:
        for n, c in run:
            print(f"{n}: {c}")
        for n, c, why in skipped:
            print(f"{n}: not run ({why}): {c}")
        return
    if len(run) < 10:
        sys.exit(f"only {len(run)} commands found in the READMEs' ```sh blocks: the extraction is broken")
    failures = []
    source_before = git_status()
    with tempfile.TemporaryDirectory(prefix="readme_") as d:
        for sub in ("scenarios", "tests", "tools"):
            os.symlink(os.path.join(ROOT, sub), os.path.join(d, sub))
        os.mkdir(os.path.join(d, "build"))
        os.symlink(os.path.abspath(SOADYN), os.path.join(d, "build", "soadyn"))
        written = {}  # file → the command that wrote it
        for n, cmd in run:
            before = snapshot(d)
            t0 = time.time()
            env = dict(os.environ, MPLBACKEND="Agg")
            if os.environ.get("SOADYN_PYTHONPATH"):
                env["PYTHONPATH"] = os.environ["SOADYN_PYTHONPATH"]
            p = subprocess.run(["bash", "-c", cmd], cwd=d, capture_output=True, text=True, timeout=900, env=env)
            after = snapshot(d)
            status = "ok" if p.returncode == 0 else f"exit status {p.returncode}"
            print(f"{n}: {status} in {time.time() - t0:.1f} s: {cmd}")
            if p.returncode != 0:
                failures.append(f"{n}: {cmd}: exit status {p.returncode}\n{p.stderr.strip()}")
            for path, sig in after.items():
                if path in before and before[path] != sig and path in written:
                    failures.append(f"{n}: {cmd}: overwrites {path}, written by {written[path]}")
                if path not in before or before[path] != sig:
                    written.setdefault(path, n)
    if source_before is not None and git_status() != source_before:
        failures.append("README's commands changed the source tree:\n" + git_status())
    for n, c, why in skipped:
        print(f"{n}: not run ({why}): {c}")
    if failures:
        print("\n".join(["", "FAILED:"] + failures))
        sys.exit(1)
    print(f"all {len(run)} README commands ran; {len(skipped)} not run (listed above)")


if __name__ == "__main__":
    main()
