"""A sweep's output directory (soadyn._sweep): the lock that keeps a second sweep out, the
fingerprint that ties DIR to one sweep, the parts (one JSON file per finished batch, written
atomically and checked row by row when read back, MAX_PART_BYTES at most), and results.h5, the
table rebuilt from them."""
from __future__ import annotations

import contextlib
import fcntl
import glob
import json
import os
import stat
import tempfile
import time
from typing import Dict, List, Optional

import numpy as np

from ._soadyn import Error, __version__
from ._cases import RESULT_COLUMNS
from ._yaml_doc import printable, read_text
from .ensemble import Sweep

MAX_PART_BYTES = 1 << 30  # a part file (a batch's rows, ~0.5 kB each)


def _lock(sw: Sweep, out: str) -> int:
    """Take DIR/sweep.lock for this sweep (an exclusive flock, held until the returned descriptor
    is closed, by this process's end at the latest) and write this process's pid and sweep file
    in it; a sweep that holds it already is named in the refusal."""
    path = os.path.join(out, "sweep.lock")
    try:
        # no O_TRUNC: the lock's holder wrote its name there; O_NOFOLLOW, O_NONBLOCK: never a
        # symlink's target, never wait on a FIFO
        fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC, 0o644)
    except OSError as e:
        raise Error(f"{path}: cannot open the sweep's lock file: {e.strerror}") from None
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise Error(f"{path}: not a regular file: remove it (a sweep keeps its lock there)")
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise Error(f"{out}: in use by another sweep ({_owner(fd)}): wait for it to end, or give another -o") from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"pid {os.getpid()}\nsweep {os.path.abspath(sw.path)}\n".encode("utf-8", "surrogateescape"), 0)
    except BaseException:
        os.close(fd)
        raise
    return fd


def _owner(fd: int) -> str:
    """'pid N, SWEEP' from a lock file its holder has written (it writes just after locking)"""
    for _ in range(20):
        text = os.pread(fd, 4096, 0).decode("utf-8", "replace")
        fields = dict(line.split(" ", 1) for line in text.splitlines() if " " in line)
        if "pid" in fields:
            return printable(f"pid {fields['pid']}" + (f", {fields['sweep']}" if "sweep" in fields else ""))
        time.sleep(0.05)
    return "pid not written yet"


def _open_store(sw: Sweep, out: str, drop_bad_parts: bool = False, say=None) -> Dict[int, dict]:
    """Check DIR holds this sweep (or nothing yet); return the rows already done.  The caller
    holds DIR's lock."""
    os.makedirs(os.path.join(out, "parts"), exist_ok=True)
    manifest = os.path.join(out, "sweep.json")
    info = {"fingerprint": sw.fingerprint(), "cases": len(sw.cases), "sweep": os.path.abspath(sw.path),
            "soadyn": __version__}
    if os.path.lexists(manifest):
        try:
            old = json.loads(read_text(manifest))
        except ValueError as e:
            raise Error(f"{manifest}: not a sweep's manifest ({e}): give another -o, or remove {out} "
                        f"if it holds nothing of yours") from None
        if not isinstance(old, dict) or not isinstance(old.get("fingerprint"), str):
            raise Error(f"{manifest}: not a sweep's manifest (no fingerprint): give another -o")
        if old.get("fingerprint") != info["fingerprint"]:
            raise Error(f"{out}: holds the results of another sweep ({printable(str(old.get('sweep')))}, fingerprint "
                        f"{printable(old['fingerprint'])}; this one is {info['fingerprint']}): give another -o or remove it")
    else:
        _write_atomic(manifest, json.dumps(info, indent=1))
    _remove_stale_temporaries(out)
    return _read_parts(out, len(sw.cases), drop_bad_parts, say)


def _remove_stale_temporaries(out: str):
    """With DIR's lock held, the temporary files in DIR and DIR/parts (NAME.XXXXXXXX.tmp, see
    _temporary) are those of writers killed before they renamed theirs: removed (a symlink's target
    is never touched: the link itself goes)."""
    for folder in (out, os.path.join(out, "parts")):
        for name in glob.glob(os.path.join(glob.escape(folder), "*.tmp")):
            try:
                if not stat.S_ISDIR(os.lstat(name).st_mode):
                    os.unlink(name)
            except OSError:
                pass


def check_results_path(sw: Sweep, path: str, force: bool = False):
    """Refuse, before any case runs, a DIR/results.h5 that is not a soadyn sweep's table (HDF5 with
    the attributes soadyn_version and fingerprint and the group /cases) unless force; never an input
    of the sweep (its sweep or scenario file, under any name), a directory, a FIFO or a device."""
    try:
        st = os.lstat(path)
    except OSError:  # nothing there, or DIR is no folder (the results directory's own check says so)
        return
    for given in (sw.path, sw.scenario_path):
        try:
            if os.path.samefile(path, given):
                raise Error(f"{path}: the output is the input file {given} (the same file, under any name); give another -o")
        except OSError:
            pass
    if stat.S_ISDIR(st.st_mode):
        raise Error(f"{path}: is a directory, expected the sweep's table (a file): remove it or give another -o")
    if stat.S_ISLNK(st.st_mode):
        why = "a symbolic link (replaced by the table, its target left as it is, only with --force)"
    elif not stat.S_ISREG(st.st_mode):
        raise Error(f"{path}: not a regular file (a FIFO, device or socket): remove it or give another -o")
    else:
        why = _foreign_results(path, st.st_size)
    if why and not force:
        raise Error(f"{path}: exists and is {why}, not a soadyn sweep's table; refusing to replace it "
                    f"(remove it, give another -o, or give --force)")


def _foreign_results(path: str, size: int) -> str:
    """'' for a soadyn sweep's results.h5 (or an empty file), else what it is"""
    if size == 0:
        return ""
    try:
        with open(path, "rb", opener=lambda p, f: os.open(p, f | os.O_NOFOLLOW | os.O_NONBLOCK)) as f:
            head = f.read(8)
    except OSError as e:
        return f"unreadable ({e.strerror})"
    if head != b"\x89HDF\r\n\x1a\n":
        return "not an HDF5 file"
    import h5py
    try:
        with h5py.File(path, "r") as f:
            if "soadyn_version" in f.attrs and "fingerprint" in f.attrs and isinstance(f.get("cases"), h5py.Group):
                return ""
    except Exception:  # noqa: BLE001 - h5py's errors for a damaged file vary
        return "a damaged HDF5 file"
    return "an HDF5 file"


# a result column's JSON types (the rest: numbers, NaN and infinities included) and their name
_COLUMN_TYPES = {"status": (str,), "reference_status": (str,), "completed": (bool,), "steps": (int,),
                 "rhs_evals": (int,)}
_TYPE_NAMES = {(str,): "text", (bool,): "true or false", (int,): "an integer", (int, float): "a number"}


def _bad_row(row, ncases: int) -> Optional[str]:
    """what makes `row` not a row this sweep wrote (None if it is one)"""
    if not isinstance(row, dict):
        return "expected a mapping of columns"
    for c in ("case",) + RESULT_COLUMNS:
        if c not in row:
            return f"missing column '{c}'"
    extra = [c for c in row if c != "case" and c not in RESULT_COLUMNS]
    if extra:
        return f"unknown column '{extra[0]}'"
    case = row["case"]
    if not isinstance(case, int) or isinstance(case, bool):
        return f"case: expected a case number, got {printable(json.dumps(case)[:40])}"
    if not 0 <= case < ncases:
        return f"case {case}: out of range (the sweep has {ncases} cases, 0 to {ncases - 1})"
    for c in RESULT_COLUMNS:
        v, types = row[c], _COLUMN_TYPES.get(c, (int, float))
        if not isinstance(v, types) or (isinstance(v, bool) and bool not in types):
            return f"case {case}: column '{c}': expected {_TYPE_NAMES[types]}, got {printable(json.dumps(v)[:40])}"
    return None


def _read_parts(out: str, ncases: int, drop_bad_parts: bool = False, say=None) -> Dict[int, dict]:
    """The rows in DIR/parts, by case.  A part that is not what this sweep writes (see the module's
    docstring) stops the sweep naming it; with drop_bad_parts it is set aside as NAME.bad."""
    done: Dict[int, dict] = {}
    for part in sorted(glob.glob(os.path.join(glob.escape(out), "parts", "*.json"))):
        rows, problem = None, None
        try:
            rows = json.loads(read_text(part, MAX_PART_BYTES))
        except RecursionError:
            problem = "not a part: its JSON is nested too deeply"
        except json.JSONDecodeError as e:
            problem = f"not valid JSON (line {e.lineno}, column {e.colno}: {e.msg})"
        except ValueError as e:  # read_text's reasons
            problem = str(e)
        if problem is None and not isinstance(rows, list):
            problem = "expected a list of rows"
        if problem is None:
            for k, row in enumerate(rows):
                bad = _bad_row(row, ncases)
                if bad:
                    problem = f"row {k + 1}: {bad}"
                    break
        if problem is None:
            for row in rows:
                done[row["case"]] = row
            continue
        if not drop_bad_parts:
            raise Error(f"{part}: {problem}: not a part this sweep wrote; run again with --drop-bad-parts to set it "
                        f"aside as {os.path.basename(part)}.bad and run its cases again (or remove it)")
        aside, k = part + ".bad", 1
        while os.path.lexists(aside):  # an earlier part of that name set aside: keep both
            aside, k = f"{part}.bad{k}", k + 1
        os.rename(part, aside)
        if say:
            say(f"set aside {part} ({problem}) as {os.path.basename(aside)}: its cases run again")
    return done


def _temporary(path: str):
    """A new file beside `path` to build it under: (descriptor, name).  tempfile.mkstemp opens with
    O_CREAT | O_EXCL | O_NOFOLLOW under a random name NAME.XXXXXXXX.tmp, so it never writes
    through a symlink or into another writer's file (a worker's, a second sweep's)."""
    d, base = os.path.split(path)
    fd, tmp = tempfile.mkstemp(prefix=base + ".", suffix=".tmp", dir=d or ".")
    os.fchmod(fd, 0o644)
    return fd, tmp


@contextlib.contextmanager
def _replaced(path: str, mode: str):
    """An open file object that becomes `path` whole: written under a _temporary() name, synced and
    renamed onto path when the block ends; removed, path untouched, when the block raises."""
    fd, tmp = _temporary(path)
    try:
        with os.fdopen(fd, mode, **({} if "b" in mode else {"encoding": "utf-8"})) as f:
            yield f
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        _unlink_quietly(tmp)
        raise


def _write_atomic(path: str, text: str):
    with _replaced(path, "w") as f:
        f.write(text)


def _unlink_quietly(path: str):
    try:
        os.unlink(path)
    except OSError:
        pass


def _save_part(out: str, rows: List[dict]):
    ids = [r["case"] for r in rows]
    _write_atomic(os.path.join(out, "parts", f"cases-{min(ids):07d}-{max(ids):07d}-{len(ids)}.json"), json.dumps(rows))


def _table(sw: Sweep, rows: Dict[int, dict]) -> Dict[str, np.ndarray]:
    ids = sorted(rows)
    table: Dict[str, np.ndarray] = {"case": np.array(ids, dtype=np.int64)}
    for p in sw.paths:
        col = [sw.cases[i][p] for i in ids]
        # numbers as float64; text, booleans, lists (gravity: [0, 0, -9.81]) as objects
        numbers = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in col)
        table[p] = np.array(col, dtype=np.float64) if numbers else _objects(col)
    for c in RESULT_COLUMNS:
        col = [rows[i][c] for i in ids]
        dtype = {"status": object, "reference_status": object, "completed": bool, "steps": np.int64,
                 "rhs_evals": np.int64}.get(c, np.float64)
        table[c] = np.array(col, dtype=dtype)
    return table


def _objects(col: list) -> np.ndarray:
    out = np.empty(len(col), dtype=object)
    out[:] = col  # element by element: a list stays one element, not a row of a 2-D array
    return out


def write_results(sw: Sweep, table: Dict[str, np.ndarray], path: str):
    """The table as HDF5: /cases/<column> datasets (strings UTF-8), the sweep and scenario texts."""
    import h5py
    with _replaced(path, "w+b") as fo:  # HDF5 writes through this file object: no name to follow
        with h5py.File(fo, "w") as f:
            _write_table(f, sw, table)


def _write_table(f, sw: Sweep, table: Dict[str, np.ndarray]):
    """The table into an open h5py file: /cases/<column> datasets (strings UTF-8), the sweep and
    scenario texts."""
    import h5py
    f.attrs["soadyn_version"] = __version__
    f.attrs["fingerprint"] = sw.fingerprint()
    f.attrs["sweep"] = sw.text
    f.attrs["scenario"] = sw.scenario_text
    f.attrs["varied"] = json.dumps(sw.paths)
    g = f.create_group("cases")
    for name, col in table.items():
        if col.dtype == object:
            text = [v if isinstance(v, str) else json.dumps(v) for v in col]  # a list as JSON
            g.create_dataset(name, data=np.array(text, dtype=h5py.string_dtype()))
        else:
            g.create_dataset(name, data=col)


def read_results(path: str) -> Dict[str, np.ndarray]:
    """A sweep's results.h5 as column name -> numpy array (strings as str)."""
    import h5py
    with h5py.File(path, "r") as f:
        order = ["case"] + json.loads(f.attrs["varied"]) + list(RESULT_COLUMNS)
        g = f["cases"]
        out = {}
        for name in order:
            d = g[name]
            out[name] = d.asstr()[()] if h5py.check_string_dtype(d.dtype) else d[()]
        return out
