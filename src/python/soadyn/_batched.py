"""A sweep task's cases run together: those that differ only in their initial state.

Cases whose values differ only in initial.q.JOINT, initial.qd.JOINT, initial.q[i] or
initial.qd[i] of one-DOF joints, each a finite number within the scenario parser's bound, are one
group: their scenario (everything but those values) is parsed once, their initial states go into
one (K, nq) and one (K, nv) array, and one call of the library (simulate_states, rollout.hpp) runs
them all, each run simulate() itself from its state, and hands back what the rows need: the
summaries, E(0) and, with a reference, the samples.  The reference runs of a group likewise.
Per case that saves the parse of its scenario (~0.1 ms) and soadyn.simulate's Trajectory (every
sample's body poses, momenta, energies as numpy arrays).

The rows are those soadyn._cases.run_case gives (tests/python/test_sweep_batched.py: bit for
bit, the CPU time aside): an initial value set here lands where the parser puts it (the same
joint's slot of q0 or v0, the same double: a float's JSON text is its shortest round-trip form),
and a value the parser would refuse (not a number, a boolean, |value| > 1e6) makes its case run
alone.  So does a case whose group would be one case, and every case of a group whose scenario
does not parse (each case's own run then says why).

run_batch, the Dask task, runs a batch of cases: the groups here, the rest by soadyn._cases.run_case.
"""
from __future__ import annotations

import json
import math
import os
import warnings
from typing import Any, Dict, List, Optional, Tuple

import numpy as np
import yaml

from . import _soadyn
from ._soadyn import Error, parse_scenario
from ._cases import _CASE_PREFIX, _Copy, _text, _tokens, apply, case_path, compare_reference, empty_row, run_case
from ._yaml_doc import _FastLoader

MAX_STATE = 1e6  # kMaxStateMagnitude (scenario.hpp): the parser refuses an initial value beyond it


def _initial_path(path: str) -> bool:
    return path == "initial" or path.startswith("initial.")


def _number(value) -> bool:
    """a value the parser reads as this same double for a one-DOF joint's initial q or qd"""
    # abs() first: an int too large for a double compares exactly instead of overflowing; NaN and
    # infinities fail the comparison
    return type(value) in (int, float) and abs(value) <= MAX_STATE


def _slot(model, path: str) -> Optional[Tuple[int, int]]:
    """(0 for q or 1 for qd, its index) of an initial value of a one-DOF joint by name or index,
    else None (the case runs alone)"""
    try:
        tokens = _tokens(path)
    except ValueError:
        return None
    if len(tokens) != 3 or tokens[0] != "initial" or tokens[1] not in ("q", "qd"):
        return None
    names = list(model.q_names if tokens[1] == "q" else model.v_names)
    joints = set(model.joint_names)
    tok = tokens[2]
    if isinstance(tok, int):  # apply() names the joint of coordinate tok: its own slot when one-DOF
        index = tok if 0 <= tok < len(names) and names[tok] in joints else None
    else:  # a one-DOF joint's coordinate is named as the joint (a multi-DOF joint's as joint.part)
        index = names.index(tok) if tok in joints and names.count(tok) == 1 else None
    return None if index is None else (0 if tokens[1] == "q" else 1, index)


def _open_initial(tree: dict) -> bool:
    """the base tree takes initial values as apply() sets them: initial, q and qd mappings or absent"""
    initial = tree.get("initial")
    if initial is None:
        return True
    return isinstance(initial, dict) and all(initial.get(k) is None or isinstance(initial.get(k), dict) for k in ("q", "qd"))


def _refused(message: str) -> str:
    return "refused: " + _CASE_PREFIX.sub("", message)


def _states(scene, values: List[List[Tuple[Tuple[int, int], float]]]) -> Tuple[np.ndarray, np.ndarray]:
    """(K, nq) and (K, nv): the scene's q0 and v0 with each case's values set, in its order"""
    x = [np.tile(scene.q0, (len(values), 1)), np.tile(scene.v0, (len(values), 1))]
    for k, case in enumerate(values):
        for (which, index), v in case:
            x[which][k, index] = v
    return x[0], x[1]


def _run(scene, q0: np.ndarray, v0: np.ndarray, states: bool) -> list:
    runs = _soadyn._simulate_states(scene, scene.settings, q0, v0, threads=1, states=states)
    for refused, _, said, _, _, _ in runs:
        for w in said:  # as soadyn.simulate warns of them
            warnings.warn(w, RuntimeWarning, stacklevel=3)
    return runs


def _references(ref_scene, key: str, q0: np.ndarray, v0: np.ndarray, cache: dict) -> list:
    """(status, (t, [q v], completed) or None) of each reference run, each state's run once per task"""
    ids = [(key, q0[k].tobytes(), v0[k].tobytes()) for k in range(len(q0))]
    todo = sorted({i: k for k, i in enumerate(ids) if i not in cache}.values())
    if todo:
        for k, (refused, summary, _, _, t, y) in zip(todo, _run(ref_scene, q0[todo], v0[todo], True)):
            cache[ids[k]] = ((_refused(refused), None) if summary is None else
                             (summary["status"], (t, y, summary["completed"])))
    return [cache[i] for i in ids]


def run_together(tree: dict, model, scenario_path: str, cases: List[Tuple[int, Dict[str, Any]]],
                 reference: Optional[Dict[str, Any]], cache: dict) -> Dict[int, Dict[str, Any]]:
    """The rows (by case id) of the cases that ran in groups; the others are left to run_case.
    `cases`: (case id, every value of the case, the sweep's fixed ones included)."""
    if not _open_initial(tree):
        return {}
    groups: Dict[str, Tuple[Dict[str, Any], List[str], list]] = {}
    for cid, values in cases:
        initial = {p: v for p, v in values.items() if _initial_path(p)}
        if not initial or not all(_number(v) for v in initial.values()):
            continue
        rest = {p: v for p, v in values.items() if not _initial_path(p)}
        key = json.dumps([list(rest.items()), list(initial)])
        groups.setdefault(key, (rest, list(initial), []))[2].append((cid, list(initial.values())))
    rows: Dict[int, Dict[str, Any]] = {}
    for rest, paths, members in groups.values():
        if len(members) > 1:
            rows.update(_group(tree, model, scenario_path, rest, paths, members, reference, cache))
    return rows


def _group(tree, model, scenario_path, rest, paths, members, reference, cache) -> Dict[int, Dict[str, Any]]:
    """One group's rows, or none when its scenario does not parse or a path is not a one-DOF slot of it."""
    try:
        edited = apply(tree, model, rest)
        scene = parse_scenario(_text(edited), case_path(scenario_path))
    except (Error, ValueError, TypeError):
        return {}
    slots = [_slot(scene.model, p) for p in paths]  # the group's own model (rest may change its joints)
    if None in slots:
        return {}
    ref_scene = None
    if reference:
        copy = _Copy(edited)
        copy.child(copy.root, "simulation", {}).update(reference)
        ref_key = _text(copy.root)
        try:
            ref_scene = parse_scenario(ref_key, case_path(scenario_path))
        except (Error, ValueError):
            return {}
    q0, v0 = _states(scene, [list(zip(slots, values)) for _, values in members])
    runs = _run(scene, q0, v0, reference is not None)
    refs = _references(ref_scene, ref_key, q0, v0, cache) if ref_scene is not None else None
    rows = {}
    for k, ((cid, _), (refused, s, _, e0, t, y)) in enumerate(zip(members, runs)):
        row = empty_row()
        if s is None:
            row["status"] = _refused(refused)
        else:
            row.update(status=s["status"], completed=bool(s["completed"]), t_reached=s["t_reached"],
                       initial_energy=float(e0) if e0 == e0 else math.nan, steps=s["steps"],
                       rhs_evals=s["rhs_evals"], cpu_seconds=s["cpu_seconds"],
                       max_energy_balance_error=s["max_energy_balance_error"],
                       final_energy_balance_error=s["final_energy_balance_error"])
            if refs is not None:
                row["reference_status"], ref = refs[k]
                if ref is not None:
                    compare_reference(row, t, y, s["completed"], ref)
        row["case"] = cid
        rows[cid] = row
    return rows


def run_batch(scenario_text: str, scenario_path: str, settings: Dict[str, Any],
              cases: List[Tuple[int, Dict[str, Any]]], reference: Optional[Dict[str, Any]],
              logs_dir: Optional[str] = None, together: bool = True) -> List[Dict[str, Any]]:
    """A Dask task: run the given (case id, values) and return their rows.  Pure: the same input
    gives the same rows (CPU times aside), whichever worker runs it and however often.  Without
    logs_dir (and with together), the cases that differ only in their initial state run together,
    one library call per such group (run_together); the rest, and every case with logs_dir,
    one soadyn.simulate each: the rows are the same, bit for bit, either way."""
    tree = yaml.load(scenario_text, Loader=_FastLoader)
    model = parse_scenario(scenario_text, case_path(scenario_path)).model
    cache: dict = {}
    done: Dict[int, Dict[str, Any]] = {}
    if together and not logs_dir:
        done = run_together(tree, model, scenario_path, [(cid, dict(settings, **values)) for cid, values in cases],
                            reference, cache)
    rows = []
    for cid, values in cases:
        if cid in done:
            rows.append(done[cid])
            continue
        log = None
        if logs_dir:
            os.makedirs(logs_dir, exist_ok=True)
            log = os.path.join(logs_dir, f"case-{cid:07d}.h5")
        row = run_case(tree, model, scenario_path, dict(settings, **values), reference, log, cache)
        row["case"] = cid
        rows.append(row)
    return rows
