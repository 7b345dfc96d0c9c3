#!/usr/bin/python3
"""Mutation check: each of issue 17's honest tests fails against a deliberately broken build.

Copies the working tree (tracked and untracked, not ignored files) to a scratch directory, builds
there, checks that every test passes on the unmodified copy, then for each mutation: applies one
small patch to the scratch copy, rebuilds the one target, runs the one test, expects it to fail,
and restores the file.  The working tree itself is never written to.  (A negative mass is
refused twice, for the URDF part and for the merged body, so no one-line mutant makes the URDF
fuzzer accept it: that mutation is gone from the table.)  The scratch build goes
through ccache (CCACHE_BASEDIR: the same objects hit whatever the directory), so after a build of
the working tree (tools/setup.sh compiles through ccache too) only the mutated files compile.

    tools/mutation_check.py [--scratch DIR] [--only NAME ...] [--ci] [--list]

--ci (tools/test.sh, after ctest): every mutation's text must still be in its file (none STALE),
and the fast paths' mutants (CI below: the body-axes 𝓜 and bias, the derivatives, the adjoint's
vector products) are built and run; the rest, one rebuild each, by hand.

Prints one line per mutation (caught by which test, or SURVIVED) and exits 1 if any survived or
a test failed on the unmodified copy.  A mutation whose text is no longer in its file is reported
as STALE (the code moved: update the table below).
"""
import argparse
import os
import shutil
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PY = "/usr/bin/python3"


def gtest(binary, test_filter):
    return {"build": [binary], "run": [f"build/tests/{binary}", f"--gtest_filter={test_filter}"],
            "test": f"{binary} {test_filter}"}


CLI_ROUTES = {"build": ["soadyn_cli"], "run": [PY, "tests/cli/test_cli_routes.py", "ForwardDynamicsRoutes"],
              "test": "test_cli_routes.py ForwardDynamicsRoutes"}


def tool(name):
    return {"build": ["soadyn_cli"], "run": ["ctest", "--test-dir", "build", "-R", f"^{name}$", "--output-on-failure"],
            "test": f"ctest {name}"}


# (item of issue 17 — or 14 for issue 14's derivatives and Jacobian —, name, file, text, replacement, what the mutant breaks, test)
MUTATIONS = [
    (1, "dense-route-allocates", "src/algorithm/dynamics.cpp",
     "data.work.factor.llt.compute(data.M);", "data.work.factor.llt = Eigen::LLT<MatX>(data.M);",
     "the dense route builds a new Cholesky object (a heap matrix) on every call",
     gtest("test_no_alloc", "NoAllocation.AlgorithmsAllocateNothingPerCall")),
    (2, "quaternion-rate-sign", "include/soadyn/multibody/joint_space.hpp",
     "qd[3] = S(0.5) * (-a * x - b * y - c * z);", "qd[3] = S(0.5) * (a * x - b * y - c * z);",
     "a sign slip in the quaternion rate: |quat| no longer constant (hidden by normalized outputs)",
     gtest("test_simulation", "Satellite.QuaternionStaysUnitInTheIntegratorState")),
    (3, "h5-potential-is-kinetic", "src/io/log_layout.cpp",
     "{s.kinetic, s.potential, s.total,", "{s.kinetic, s.kinetic, s.total,",
     "/energy/potential logs the kinetic energy",
     gtest("test_h5log", "Hdf5.*")),
    (3, "h5-t-end-attribute", "src/io/h5log.cpp",
     "attribute(g_solver, name.c_str(), setting_number(settings, info));",
     "attribute(g_solver, name.c_str(), settings.output_dt);",
     "/solver's numbers (t_end among them) all hold the output interval",
     gtest("test_h5log", "Hdf5.*")),
    (4, "velocity-product-term", "src/algorithm/kinematics.cpp",
     "wp.cross(gu) + wp.cross(Vec3(u - up));", "wp.cross(gu) - wp.cross(Vec3(u - up));",
     "a sign slip in a_i's ω_p × ḋ_i: bias and every route's q̈ wrong, yet M q̈ + bias = τ still holds",
     CLI_ROUTES),
    (4, "sparse-route-solve", "src/algorithm/ltdl.cpp",
     "for (int k = 0; k < model.nv; ++k) x(k) /= H(k, k);", "for (int k = 1; k < model.nv; ++k) x(k) /= H(k, k);",
     "the tree-sparse route forgets the first pivot",
     CLI_ROUTES),
    (5, "bdf-ignores-rtol", "src/sim/cvode.hpp",
     "rtol_(s.rtol), atol_(s.atol)", "rtol_(bdf ? 1e4 * s.rtol : s.rtol), atol_(s.atol)",
     "BDF runs at 10^4 times the requested relative tolerance",
     gtest("test_stability", "Stability.BdfOnTheStiffArmIsAccurate")),
    (6, "placement-not-turned", "src/algorithm/kinematics.cpp",
     "eta_p + Rp * model.placement[i].p + Rj * pm", "eta_p + model.placement[i].p + Rj * pm",
     "joint placements are added in world axes instead of the parent's: every η_i off, consistently",
     gtest("test_mass_matrix", "NoteExamples.Example2*:NoteExamples.Example3*:NoteExamples.Example4*")),
    (9, "plot-half-angle", "tools/plot.py",
     "theta = 2 * np.arctan2(s, q[:, 0])", "theta = np.arctan2(s, q[:, 0])",
     "plot.py's rotation vector of a free or ball joint has half its angle",
     tool("tool_plot")),
    (11, "plot-bins-shifted", "tools/plot.py",
     "starts = np.flatnonzero(np.r_[True, which[1:] != which[:-1]])",
     "starts = np.flatnonzero(np.r_[True, which[1:] != which[:-1]]); which = np.maximum(which - 1, 0)",
     "plot.py files each block's rows one pixel column early: the min/max envelope shifts",
     tool("tool_plot")),
    (11, "plot-balance-without-work", "tools/plot.py",
     '([(w, -1.0)] if w is not None else [])', '[]',
     "plot.py leaves the inputs' work out of the energy balance: the damper's work drawn as error",
     tool("tool_plot")),
    (9, "wp-error-without-velocities", "tools/work_precision.py",
     'e = np.concatenate([r["q"] - ref["q"], r["qd"] - ref["qd"]])', 'e = r["q"] - ref["q"]',
     "work_precision.py's state error leaves out the velocities",
     tool("tool_work_precision")),
    (9, "stability-bound-loose", "tools/stability.py",
     "BOUND = 0.05", "BOUND = 0.5",
     "stability.py calls a run with 50 % energy error bounded",
     tool("tool_stability")),
    (14, "ball-columns-not-carried", "include/soadyn/multibody/joint_model.hpp",
     "static constexpr bool carries(int, int) { return true; }", "static constexpr bool carries(int, int) { return false; }",
     "the derivatives treat a ball's G columns as fixed in the parent (issue 14)",
     gtest("test_derivatives", "RandomTrees/Derivatives.*ball*")),
    (14, "derivative-phi-term", "src/algorithm/derivatives.cpp",
     "dq += dd.S.col(r).dot(dd.phi.col(c));", "dq += 0.0 * dd.S.col(r).dot(dd.phi.col(c));",
     "∂τ/∂q of a multi-DOF joint loses S_mᵀ (ξ ×* F_j) on its own rows (issue 14)",
     gtest("test_derivatives", "RandomTrees/Derivatives.*")),
    (14, "jacobian-free-tangent-map", "include/soadyn/multibody/joint_space.hpp",
     "quaternion_tangent(q + 3, true);", "quaternion_tangent(q + 3, false);",
     "the ODE Jacobian chains a free joint's quaternion as a ball's (issue 14)",
     gtest("test_implicit", "SystemJacobian.*")),
    (14, "midpoint-newton-once", "src/sim/fixed_step.cpp",
     "if (full_) factor(tm, h, X);", "if (full_ && it == 0) factor(tm, h, X);",
     "full Newton keeps its first Jacobian (issue 14)",
     gtest("test_implicit", "MidpointNewton.*")),
    (14, "newton-schur-quaternion-block", "src/sim/newton_solver.cpp",
     "Gi = b.lu.solve(Jqv);", "Gi = Jqv;",
     "BDF's structured Newton solve forgets P⁻¹ = (I − γ ∂q̇/∂q)⁻¹ on a quaternion's rows (issue 14)",
     gtest("test_newton_solver", "NewtonSolver.*")),
    (36, "vjp-forgets-ancestor-rows", "src/algorithm/derivative_products.cpp",
     "+ wp.dot(dd.psi.col(c));", ";",
     "(∂τ/∂q)ᵀμ without the ancestors' rows w_p·ψ_c (issue 36)",
     gtest("test_derivatives", "RandomTrees/Derivatives.TransposeTimes*")),
    (36, "jvp-forgets-subtree-sums", "src/algorithm/derivative_products.cpp",
     "for (int j = 0; j < 6; ++j) o += In(Zi + K * j) * dd.S(j, r);", "",
     "(∂τ/∂q) x + (∂τ/∂v) y without the subtree's columns Z_i·S_r (issue 36: the forward sensitivities' products)",
     gtest("test_derivatives", "RandomTrees/Derivatives.TimesDirections*")),
    (36, "sensitivity-parameter-force-sign", "src/sim/sensitivity.cpp",
     "self->Y_ = -self->Y_;", "self->Y_ = 1.0 * self->Y_;",
     "∂q̈/∂π = +𝓜⁻¹ Y in the forward sensitivities' right-hand side (issue 36)",
     gtest("test_sensitivity", "*")),
    (36, "regressor-transpose-not-carried", "src/algorithm/regressor.cpp",
     "wi.tail<3>() += w.col(p).tail<3>() + om.cross(Vec3(data.d.col(i)));", "wi.tail<3>() += w.col(p).tail<3>();",
     "Yᵀμ carries w to the child's joint point without ω × d (issue 36)",
     gtest("test_regressor", "Trees/Regressor.TransposeTimes*")),
    (36, "regressor-listed-gravity-sign", "src/algorithm/regressor.cpp",
     "data.A.col(b).tail<3>() = eta_dd - model.gravity;", "data.A.col(b).tail<3>() = eta_dd + model.gravity;",
     "the listed bodies' regressor columns with gravity's base acceleration the wrong way (issue 36)",
     gtest("test_regressor", "Trees/Regressor.ListedBodies*")),
    (36, "fixed-point-last-iterate-left", "src/sim/fixed_point.cpp",
     "    if (last != ycor) N_VScale(1.0, last, ycor);", "    (void)last;",
     "the fixed-point corrector leaves an odd iteration's result in its own buffer (issue 36)",
     gtest("test_fixed_point", "FixedPoint.*")),
    (36, "adjoint-vjp-sign", "src/sim/adjoint.cpp",
     "      a.g_ = -a.g_;", "",
     "the adjoint's λ_vᵀ ∂q̈/∂q with the wrong sign (issue 36)",
     gtest("test_adjoint", "Adjoint.*")),
    # the fast paths (issue 30, item 7): body-axes 𝓜 and bias against their inertial references
    (30, "local-mass-turned-product", "src/algorithm/joint_local.hpp",
     "I[a][b] = dif * s2 + iab * c2;", "I[a][b] = dif * s2 - iab * c2;",
     "the body-axes 𝓜 turns a composite's off-diagonal inertia I_ab with the wrong sign",
     gtest("test_mass_matrix_local", "Trees/LocalRoute.*")),
    (30, "local-mass-column-turn", "src/algorithm/joint_local.hpp",
     "n[a] = c * x[a] - s * x[b], n[b] = s * x[a] + c * x[b];", "n[a] = c * x[a] - s * x[b], n[b] = s * x[a] - c * x[b];",
     "the body-axes 𝓜 turns a carried column's moment wrongly on the way to the parent",
     gtest("test_mass_matrix_local", "Trees/LocalRoute.*")),
    (30, "local-bias-turn-back", "src/algorithm/bias_local.cpp",
     "y(k) = x(k), y(a) = c * x(a) + s * x(b), y(b) = c * x(b) - s * x(a);",
     "y(k) = x(k), y(a) = c * x(a) + s * x(b), y(b) = c * x(b) + s * x(a);",
     "the body-axes bias turns the parent's motion into the child's axes by a non-rotation",
     gtest("test_bias_local", "*BodyAxesBias.*")),
    (30, "local-bias-gyroscopic", "src/algorithm/bias_local.cpp",
     "w.cross(hn) + u.cross(hf);", "w.cross(hn);",
     "the body-axes bias force loses u ×* f, the linear part of v ×* M v",
     gtest("test_bias_local", "*BodyAxesBias.*")),
    (31, "fd-derivatives-subtree-sum", "src/algorithm/forward_derivatives.cpp",
     "for (int k = 0; k < nv; ++k) Pp[c * ld + k] += Pj[c * ld + k];",
     "for (int k = 0; k < nv; ++k) Pp[c * ld + k] += 0.0 * Pj[c * ld + k];",
     "∂q̈/∂q and ∂q̈/∂v lose a branch's subtree sum 𝒫 at its parent (another path's block)",
     gtest("test_derivatives", "RandomTrees/Derivatives.*")),
]


# the mutants tools/test.sh runs in CI (each costs one recompiled file and one test)
CI = {"local-mass-turned-product", "local-mass-column-turn", "local-bias-turn-back", "local-bias-gyroscopic",
      "fd-derivatives-subtree-sum", "derivative-phi-term", "vjp-forgets-ancestor-rows", "jvp-forgets-subtree-sums",
      "regressor-transpose-not-carried", "sparse-route-solve"}


def sh(cmd, cwd, log, env=None, timeout=3600, expect=None):
    """run cmd, its output appended to the log; with `expect`, a failure counts only if the output says so"""
    with open(log, "a") as f:
        f.write(f"\n$ {' '.join(cmd)}\n")
        f.flush()
        try:
            p = subprocess.run(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=env,
                               timeout=timeout, text=True, errors="replace")
        except subprocess.TimeoutExpired:
            f.write("timed out\n")
            return 124
        f.write(p.stdout)
        if p.returncode != 0 and expect and expect not in p.stdout:
            f.write(f"(failed, but without '{expect}': not counted as caught)\n")
            return 0
        return p.returncode


def copy_tree(scratch):
    files = subprocess.run(["git", "ls-files", "-co", "--exclude-standard", "-z"], cwd=ROOT, check=True,
                           capture_output=True).stdout.split(b"\0")
    for rel in (f.decode() for f in files if f):
        src, dst = os.path.join(ROOT, rel), os.path.join(scratch, rel)
        if not os.path.isfile(src):
            continue
        os.makedirs(os.path.dirname(dst), exist_ok=True)
        if not os.path.exists(dst) or open(src, "rb").read() != open(dst, "rb").read():
            shutil.copy2(src, dst)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scratch", default=os.path.join(os.environ.get("TMPDIR", "/tmp"), "soadyn_mutation"))
    ap.add_argument("--only", nargs="*", help="names of the mutations to run (default: all)")
    ap.add_argument("--ci", action="store_true", help="no mutation stale; run the fast paths' mutants (CI)")
    ap.add_argument("--list", action="store_true")
    args = ap.parse_args()
    if args.ci:
        stale = [f"{name} ({path})" for _, name, path, old, *_ in MUTATIONS
                 if open(os.path.join(ROOT, path), encoding="utf-8").read().count(old) != 1]
        if stale:
            print("mutation_check: STALE (the text to mutate is not once in its file; update MUTATIONS): "
                  + ", ".join(stale))
            return 1
        print(f"mutation_check: all {len(MUTATIONS)} mutations still apply; running the {len(CI)} of CI")
    chosen = [m for m in MUTATIONS if (not args.only or m[1] in args.only) and (not args.ci or m[1] in CI)]
    if args.list:
        for item, name, path, *_ , what, t in chosen:
            print(f"item {item}  {name:28s} {path:24s} {t['test']}\n    {what}")
        return 0
    scratch = os.path.abspath(args.scratch)
    if os.path.commonpath([scratch, ROOT]) == ROOT:
        sys.exit("mutation_check: the scratch directory must be outside the working tree")
    os.makedirs(scratch, exist_ok=True)
    copy_tree(scratch)
    log = os.path.join(scratch, "mutation_check.log")
    open(log, "w").close()
    env = dict(os.environ, CCACHE_BASEDIR=scratch, SOADYN=os.path.join(scratch, "build", "soadyn"),
               SOADYN_SOURCE_DIR=scratch, MPLBACKEND="Agg")
    print(f"scratch copy: {scratch}  (log: {log})")
    if sh(["cmake", "-S", ".", "-B", "build", "-DCMAKE_BUILD_TYPE=Release", "-DSOADYN_WERROR=ON",
           "-DSOADYN_BUILD_TESTS=ON", "-DSOADYN_BUILD_BENCH=OFF",
           *(["-DCMAKE_CXX_COMPILER_LAUNCHER=ccache"] if shutil.which("ccache") else [])],  # without it: a full build
          scratch, log, env) != 0:
        sys.exit("mutation_check: cmake failed (see the log)")

    def build(t):
        return sh(["nice", "cmake", "--build", "build", "-j2", "--target", *t["build"]], scratch, log, env)

    # the unmodified copy: every test used must build and pass, or a failure below means nothing
    tests = {}
    for m in chosen:
        tests.setdefault(m[6]["test"], m[6])
    for t in tests.values():
        if build(t) != 0 or sh(t["run"], scratch, log, env) != 0:
            print(f"BASELINE FAILED: {t['test']} fails on the unmodified copy (see the log)")
            return 1
        print(f"baseline passes: {t['test']}")

    survived = 0
    for item, name, path, old, new, what, t in chosen:
        target = os.path.join(scratch, path)
        original = open(target, encoding="utf-8").read()
        if original.count(old) != 1:
            print(f"item {item}  {name:28s} STALE: the text to mutate is not (once) in {path}")
            survived += 1
            continue
        start = time.time()
        try:
            with open(target, "w", encoding="utf-8") as f:
                f.write(original.replace(old, new))
            if build(t) != 0:
                verdict = "BROKEN: the mutant does not build (fix the table below)"
            else:
                rc = sh(t["run"], scratch, log, env, expect=t.get("expect"))
                verdict = f"caught by {t['test']} (exit {rc})" if rc != 0 else f"SURVIVED {t['test']}"
        finally:
            with open(target, "w", encoding="utf-8") as f:
                f.write(original)
        survived += verdict.startswith(("SURVIVED", "BROKEN"))
        print(f"item {item}  {name:28s} {verdict}  [{time.time() - start:.0f} s]\n    mutant: {what}", flush=True)
    return 1 if survived else 0


if __name__ == "__main__":
    sys.exit(main())
