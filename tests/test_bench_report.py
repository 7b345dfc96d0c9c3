#!/usr/bin/python3
"""tools/bench/report.py on a Google Benchmark JSON written here: with repetitions, every figure is
the fastest repetition of its benchmark, the ratio to the fastest peer is formed from those, and
--keep writes exactly those entries; a case that could not run is "failed" in its cell with its reason
listed once."""
import json
import os
import subprocess
import sys
import tempfile

REPORT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tools", "bench", "report.py")


def entry(name, ns, rep, reps):
    return {"name": name, "run_name": name, "run_type": "iteration", "repetitions": reps,
            "repetition_index": rep, "real_time": ns, "cpu_time": ns, "time_unit": "ns"}


def main():
    times = {  # three interleaved repetitions each; the slow ones stand for a burst of load
        "chain/mass_composite/1": [100.0, 80.0, 120.0],
        "peer/chain/mass/soadyn/1": [50.0, 40.0, 90.0],
        "peer/chain/mass/rbdl/1": [60.0, 33.0, 31.0],
        "peer/chain/mass/mujoco/1": [200.0, 35.0, 210.0],
    }
    benchmarks = [entry(n, t, r, 3) for r in range(3) for n, ts in times.items() for t in [ts[r]]]
    # a case that could not run (soadyn_bench marks it with SkipWithError): "failed" in its cell, the reason listed
    for r in range(3):
        benchmarks.append({"name": "chain/mass_composite/2", "run_name": "chain/mass_composite/2", "run_type": "iteration",
                           "repetitions": 3, "repetition_index": r, "error_occurred": True,
                           "error_message": "symplectic-euler on the 2-link chain at dt 1e-3 failed: Newton did not converge"})
    benchmarks.append({"name": "peer/chain/mass/soadyn/1_mean", "run_name": "peer/chain/mass/soadyn/1",
                       "run_type": "aggregate", "aggregate_name": "mean", "real_time": 60.0, "time_unit": "ns"})
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "bench.json")
        with open(path, "w") as f:
            json.dump({"context": {"date": "today", "num_cpus": 2, "mhz_per_cpu": 2000,
                                   "peer_rbdl": "RBDL", "peer_mujoco": "MuJoCo"}, "benchmarks": benchmarks}, f)
        keep = os.path.join(tmp, "kept.json")
        subprocess.run([sys.executable, REPORT, path, "-o", tmp, "--keep", keep], check=True,
                       stdout=subprocess.DEVNULL, env=dict(os.environ, MPLBACKEND="Agg"))
        md = open(os.path.join(tmp, "bench.md")).read()
        csv = open(os.path.join(tmp, "bench.csv")).read()
        kept = {b["name"]: b.get("real_time") for b in json.load(open(keep))["benchmarks"]}
    assert "fastest of 3 repetitions" in md, md
    assert "chain/mass_composite,1,80.0" in csv and "chain/mass_composite,2" not in csv, csv
    table = next(line for line in md.splitlines() if line.startswith("| mass_composite | "))
    assert [c.strip() for c in table.strip("|").split("|")][1:3] == ["80", "failed"], table
    assert md.count("Not timed: symplectic-euler on the 2-link chain at dt 1e-3 failed: Newton did not converge.") == 1, md
    # soadyn 40 against rbdl's 31 (mujoco's best, 35, is slower): 40 / 31 = 1.29
    row = next(line for line in md.splitlines() if line.startswith("| chain N=1 | "))
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert cells[1:5] == ["40", "31", "rbdl", "1.29"], row
    # --keep: one entry per benchmark, its fastest repetition, no aggregates
    assert kept == {**{name: min(ts) for name, ts in times.items()}, "chain/mass_composite/2": None}, kept
    print("report.py keeps the fastest repetition:", row)


if __name__ == "__main__":
    main()
