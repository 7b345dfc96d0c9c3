"""A sweep's cases (soadyn.ensemble): a case's {field path: value} applied to the base scenario's
YAML tree (path copying: the base is shared, never changed), the edited tree parsed and run, and
the case's row of results (RESULT_COLUMNS), with its state error against a reference run.
The Dask task that runs a batch of cases on a worker, run_batch, is soadyn._batched's (it groups
the cases that run together, and runs the others here)."""
from __future__ import annotations

import functools
import json
import math
import os
import re
from typing import Any, Dict, List, Optional, Tuple

import numpy as np

from ._soadyn import Error, parse_scenario
from ._yaml_doc import _clip

RESULT_COLUMNS = ("status", "completed", "initial_energy", "t_reached", "steps", "rhs_evals", "cpu_seconds",
                  "max_energy_balance_error", "final_energy_balance_error", "state_error", "final_state_error", "reference_status")


# ---------------------------------------------------------------- field paths, and a tree as the parser's text

_SEGMENT = re.compile(r"([^.\[\]]+)((?:\[-?\d+\])*)")


def parse_path(path: str) -> List[Any]:
    """'inputs.springs[0].stiffness' -> ['inputs', 'springs', 0, 'stiffness']."""
    tokens: List[Any] = []
    for seg in path.split("."):
        m = _SEGMENT.fullmatch(seg)
        if not m:
            raise ValueError(f"bad path segment '{_clip(seg)}' (expected name or name[index])")
        tokens.append(m.group(1))
        for i in re.findall(r"\[(-?\d+)\]", m.group(2)):
            # Python's count from the end would silently pick the last coordinate or entry
            if i.startswith("-"):
                raise ValueError(f"{_clip(m.group(1))}[{i}]: a negative index; entries count from 0 (write the index itself)")
            tokens.append(int(i))
    return tokens


def _text(tree: dict) -> str:
    """A scenario tree as text for the parser: JSON, which is YAML (and 100× faster than PyYAML's dump)."""
    return json.dumps(tree, allow_nan=False)


_CASE_PREFIX = re.compile(r"^.*?<case>:\d+:\d+: ")


def case_path(scenario_path: str) -> str:
    """The name a case's edited scenario is parsed under: beside the base (a relative urdf: holds)."""
    return os.path.join(os.path.dirname(scenario_path), "<case>")


# ---------------------------------------------------------------- applying a case to the scenario tree

def _vector_slot(model, which: str, index: int):
    """(joint name, component or None for a 1-DOF joint, the joint's neutral entries) of q[index]
    or qd[index], from the model's coordinate names (joint, or joint.component)."""
    names = list(model.q_names if which == "q" else model.v_names)
    if not 0 <= index < len(names):
        raise ValueError(f"initial.{which}[{index}]: index out of range (the model has {len(names)})")
    joint = names[index] if names[index] in model.joint_names else names[index].rsplit(".", 1)[0]
    if joint == names[index]:
        return joint, None, None
    first = next(k for k, n in enumerate(names) if n.startswith(joint + "."))
    count = sum(1 for n in names if n.startswith(joint + "."))
    neutral = [float(x) for x in model.neutral()[first:first + count]] if which == "q" else [0.0] * count
    return joint, index - first, neutral


class _Copy:
    """A copy of a scenario tree that shares every container it has not edited with the base
    (path copying: an edit copies only the mappings and lists on its path, not the whole tree)."""

    def __init__(self, tree: dict):
        self.root = dict(tree)
        self._own = {id(self.root)}

    def child(self, node, key, default=None):
        """node[key] made this copy's own (node itself must be); `default` (a new container) when
        it is absent or null, None when it is absent and there is no default."""
        value = node.get(key) if isinstance(node, dict) else node[key]
        if value is None and default is not None:
            value = default
        elif isinstance(value, (dict, list)) and id(value) not in self._own:
            value = dict(value) if isinstance(value, dict) else list(value)
        else:
            return value
        node[key] = value
        self._own.add(id(value))
        return value


@functools.lru_cache(maxsize=4096)
def _tokens(path: str) -> Tuple[Any, ...]:
    return tuple(parse_path(path))


def apply(tree: dict, model, values: Dict[str, Any]) -> dict:
    """A copy of the scenario tree with each {path: value} set (the base tree is left unchanged)."""
    out = _Copy(tree)
    for path, value in values.items():
        tokens = _tokens(path)
        if len(tokens) == 3 and tokens[0] == "initial" and tokens[1] in ("q", "qd") and isinstance(tokens[2], int):
            joint, comp, neutral = _vector_slot(model, tokens[1], tokens[2])
            vec = out.child(out.child(out.root, "initial", {}), tokens[1], {})
            if comp is None:
                vec[joint] = value
            else:
                cur = list(vec.get(joint, neutral))
                cur[comp] = value
                vec[joint] = cur
            continue
        node = out.root
        for i, tok in enumerate(tokens):
            last = i == len(tokens) - 1
            where = ".".join(str(t) for t in tokens[:i + 1])
            if isinstance(tok, int):
                if not isinstance(node, list) or not 0 <= tok < len(node):
                    raise ValueError(f"{_clip(where, 80)}: no entry [{tok}] (the scenario has "
                                     f"{len(node) if isinstance(node, list) else 'no list'} here)")
                if last:
                    node[tok] = value
                else:
                    node = out.child(node, tok)
            elif isinstance(node, list):  # a list entry by its name (bodies) or joint (inputs)
                match = [k for k, e in enumerate(node) if isinstance(e, dict) and tok in (e.get("name"), e.get("joint"))]
                if len(match) != 1:
                    names = [_clip(str(e.get("name", e.get("joint")))) for e in node if isinstance(e, dict)]
                    shown = ", ".join(names[:20]) + (f", … ({len(names)} in all)" if len(names) > 20 else "")
                    raise ValueError(f"{'no' if not match else 'more than one'} entry named '{_clip(tok)}' "
                                     f"(the scenario has {shown})")
                if last:
                    raise ValueError(f"{_clip(where, 80)} names a whole entry; name a field of it")
                node = out.child(node, match[0])
            elif isinstance(node, dict):
                if last:
                    node[tok] = value
                else:
                    if node.get(tok) is None:
                        if tok in ("initial", "simulation", "q", "qd"):
                            node = out.child(node, tok, {})
                            continue
                        raise ValueError(f"the scenario has no '{_clip(where, 80)}'")
                    node = out.child(node, tok)
            else:
                raise ValueError(f"'{_clip('.'.join(str(t) for t in tokens[:i]), 80)}' is a value, not a mapping or list")
    return out.root


# ---------------------------------------------------------------- running cases (on a worker)

def _state(traj) -> np.ndarray:
    return np.hstack([traj.q, traj.v])


def empty_row() -> Dict[str, Any]:
    """A case's row before its run (a refused case keeps it so, with its status)."""
    return {"status": "", "completed": False, "initial_energy": math.nan, "t_reached": math.nan, "steps": 0,
            "rhs_evals": 0, "cpu_seconds": math.nan, "max_energy_balance_error": math.nan,
            "final_energy_balance_error": math.nan, "state_error": math.nan, "final_state_error": math.nan,
            "reference_status": ""}


def compare_reference(row: Dict[str, Any], t: np.ndarray, y: np.ndarray, completed: bool, ref) -> None:
    """The row's state errors: the run's samples (t, y = [q v] per row) against its reference run's
    (t_ref, y_ref, whether it completed): the largest difference over the common output times,
    and at t_end when both completed."""
    t_ref, y_ref, ref_done = ref
    # the samples at common times (a step that does not divide output_dt samples at step
    # times; every run that completes has its last sample at t_end)
    k = np.clip(np.searchsorted(t_ref, t), 0, len(t_ref) - 1)
    same = np.abs(t_ref[k] - t) <= 1e-12 * np.maximum(1.0, np.abs(t))
    if np.any(same):
        diff = np.abs(y[same] - y_ref[k[same]])
        row["state_error"] = float(np.max(diff)) if np.all(np.isfinite(diff)) else math.inf
    if completed and ref_done:
        row["final_state_error"] = float(np.max(np.abs(y[-1] - y_ref[-1])))


def run_case(sweep_tree: dict, model, scenario_path: str, values: Dict[str, Any],
             reference: Optional[Dict[str, Any]] = None, log: Optional[str] = None,
             cache: Optional[dict] = None) -> Dict[str, Any]:
    """One case's row: status, steps, RHS evaluations, CPU time, energy errors, state error
    against the reference run (max over the common output samples, and at t_end)."""
    from . import simulate
    row = empty_row()
    try:
        tree = apply(sweep_tree, model, values)
        scene = parse_scenario(_text(tree), case_path(scenario_path))
        traj = simulate(scene, output=log)
    except (Error, ValueError, TypeError) as e:
        row["status"] = "refused: " + _CASE_PREFIX.sub("", str(e))
        return row
    s = traj.summary
    row.update(status=s.status, completed=bool(s.completed), t_reached=s.t_reached,
               initial_energy=float(traj.total_energy[0]) if len(traj.t) else math.nan, steps=s.steps,
               rhs_evals=s.rhs_evals, cpu_seconds=s.cpu_seconds, max_energy_balance_error=s.max_energy_balance_error,
               final_energy_balance_error=s.final_energy_balance_error)
    if reference:
        rtree = _Copy(tree)
        rtree.child(rtree.root, "simulation", {}).update(reference)
        key = _text(rtree.root)
        if cache is not None and key in cache:
            rstatus, ref = cache[key]
        else:
            try:
                rtraj = simulate(parse_scenario(key, case_path(scenario_path)))
                rstatus, ref = rtraj.summary.status, (rtraj.t, _state(rtraj), rtraj.summary.completed)
            except (Error, ValueError) as e:
                rstatus, ref = "refused: " + _CASE_PREFIX.sub("", str(e)), None
            if cache is not None:
                cache[key] = (rstatus, ref)
        row["reference_status"] = rstatus
        if ref is not None:
            compare_reference(row, traj.t, _state(traj), s.completed, ref)
    return row
