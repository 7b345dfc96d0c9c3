"""soadyn.batch and soadyn.rollout: many states or many runs per call, against the one-state calls.

Exact equality (==) is the claim for batched against looped: each state is computed by the same
library calls on the same numbers, only on another thread's Data, so any difference at all would be
a result leaking between states or depending on the thread.  Between two routes that differ
(rollout against simulate) the comparison has a tolerance.
"""
import os
import signal
import sys
import time

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(__file__))
from conftest import SCENARIOS, random_tree_yaml  # noqa: E402

import soadyn  # noqa: E402

THREADS = [1, 2, 3]


@pytest.fixture(scope="module")
def tree():
    """a random tree with every joint type and a free root, and K = 2001 random states: enough work
    that the batch starts its threads (it keeps a small batch on the calling thread)"""
    rng = np.random.default_rng(7)
    model = soadyn.parse_scenario(random_tree_yaml(rng, 9, free_root=True)).model
    K = 2001
    q = np.array([model.normalize(rng.uniform(-2, 2, model.nq)) for _ in range(K)])
    v = rng.uniform(-1, 1, (K, model.nv))
    x = rng.uniform(-3, 3, (K, model.nv))
    return model, q, v, x


def looped(fn, model, *arrays, **kw):
    """fn(model, data, row…) over the states in reverse order on one Data, results copied"""
    data = model.create_data()
    K = len(arrays[0])
    out = [None] * K
    for k in reversed(range(K)):
        r = fn(model, data, *(a[k] for a in arrays), **kw)
        out[k] = tuple(np.array(x) for x in r) if isinstance(r, tuple) else np.array(r)
    if isinstance(out[0], tuple):
        return tuple(np.stack([o[i] for o in out]) for i in range(len(out[0])))
    return np.stack(out)


@pytest.mark.parametrize("threads", THREADS)
def test_batched_equals_looped_to_the_bit(tree, threads):
    model, q, v, x = tree
    b = soadyn.batch
    for method in soadyn.DYNAMICS:
        assert (b.forward_dynamics(model, q, v, x, method=method, threads=threads)
                == looped(soadyn.forward_dynamics, model, q, v, x, method=method)).all(), method
    # the batched 𝓜 and bias take the body-axes routes: the single calls' kinematics=False
    assert (b.mass_matrix(model, q, threads=threads) == looped(soadyn.mass_matrix, model, q, kinematics=False)).all()
    assert (b.bias_forces(model, q, v, threads=threads) == looped(soadyn.bias_forces, model, q, v, kinematics=False)).all()
    assert (b.inverse_dynamics(model, q, v, x, threads=threads) == looped(soadyn.inverse_dynamics, model, q, v, x)).all()
    for got, ref in zip(b.inverse_dynamics_derivatives(model, q, v, x, threads=threads), looped(soadyn.inverse_dynamics_derivatives, model, q, v, x)):
        assert got.shape == ref.shape and (got == ref).all()
    fd = b.forward_dynamics_derivatives(model, q, v, x, threads=threads)
    assert len(fd) == 3
    for got, ref in zip(fd, looped(soadyn.forward_dynamics_derivatives, model, q, v, x)):
        assert got.shape == ref.shape and (got == ref).all()
    # always three results: 𝓜⁻¹ None when not asked for
    dq, dv, none = b.forward_dynamics_derivatives(model, q, v, x, minv=False, threads=threads)
    assert none is None and (dq == fd[0]).all() and (dv == fd[1]).all()


@pytest.mark.parametrize("threads", THREADS)
def test_frame_jacobians_batched_equal_looped(tree, threads):
    model, q, v, x = tree
    frame = model.frame_names[-1]
    for reference in ("world", "local", "local_world_aligned"):
        got = soadyn.batch.frame_jacobian(model, q, frame, reference=reference, threads=threads)
        ref = looped(soadyn.frame_jacobian, model, q, frame=frame, reference=reference)
        assert got.shape == (len(q), 6, model.nv) and (got == ref).all(), reference
    assert (soadyn.batch.Pool(model, threads).frame_jacobian(q[:5], len(model.frame_names) - 1)
            == soadyn.batch.frame_jacobian(model, q[:5], frame)).all()
    with pytest.raises(KeyError, match="no frame named"):
        soadyn.batch.frame_jacobian(model, q, "no such frame")
    with pytest.raises(ValueError, match="batch::frame_jacobian: frame: expected an index"):
        soadyn.batch.frame_jacobian(model, q, 10**6)


@pytest.mark.parametrize("threads", [1, 2])
def test_pool_kept_between_calls_gives_the_same_bits(tree, threads):
    model, q, v, x = tree
    pool = soadyn.batch.Pool(model, threads=threads)
    assert pool.threads == threads
    for _ in range(2):  # its Data carry over from call to call
        assert (pool.forward_dynamics(q, v, x) == soadyn.batch.forward_dynamics(model, q, v, x)).all()
        assert (pool.mass_matrix(q[:3]) == soadyn.batch.mass_matrix(model, q[:3])).all()
        assert (pool.bias_forces(q, v) == soadyn.batch.bias_forces(model, q, v)).all()
        assert (pool.inverse_dynamics(q, v, x) == soadyn.batch.inverse_dynamics(model, q, v, x)).all()
        for a, b in zip(pool.forward_dynamics_derivatives(q[:50], v[:50], x[:50]), soadyn.batch.forward_dynamics_derivatives(model, q[:50], v[:50], x[:50])):
            assert (a == b).all()
        for a, b in zip(pool.inverse_dynamics_derivatives(q[:50], v[:50], x[:50]), soadyn.batch.inverse_dynamics_derivatives(model, q[:50], v[:50], x[:50])):
            assert (a == b).all()
    with pytest.raises(ValueError, match="batch.forward_dynamics: tau"):
        pool.forward_dynamics(q, v, x[:, :2])


def test_pool_keeps_its_model_alive():
    scene = soadyn.load_scenario(f"{SCENARIOS}/double_pendulum.yaml")
    model = soadyn.load(f"{SCENARIOS}/double_pendulum.yaml")
    q, v = np.tile(scene.q0, (4, 1)), np.tile(scene.v0, (4, 1))
    ref = soadyn.batch.bias_forces(model, q, v)
    pool = soadyn.batch.Pool(model)
    del model
    import gc
    gc.collect()
    assert (pool.bias_forces(q, v) == ref).all()


def test_any_layout_and_lists_read(tree):
    model, q, v, x = tree
    ref = soadyn.batch.forward_dynamics(model, q, v, x)
    wide = np.zeros((len(q), 2 * model.nq))
    wide[:, ::2] = q  # a strided view: converted once
    assert (soadyn.batch.forward_dynamics(model, wide[:, ::2], np.asfortranarray(v), x.tolist()) == ref).all()
    assert soadyn.batch.forward_dynamics(model, q[:0], v[:0], x[:0]).shape == (0, model.nv)


def test_bad_shapes_and_values_refused_naming_the_argument(tree):
    model, q, v, x = tree
    nq, nv, K = model.nq, model.nv, len(q)
    b = soadyn.batch
    with pytest.raises(soadyn.Error, match=rf"batch.forward_dynamics: q: expected shape \(K, {nq}\).*got \({K}, {nq - 1}\)"):
        b.forward_dynamics(model, q[:, 1:], v, x)
    with pytest.raises(ValueError, match=rf"batch.bias_forces: v: expected shape \({K}, {nv}\) .*K from q.*got \(3, {nv}\)"):
        b.bias_forces(model, q, v[:3])
    with pytest.raises(ValueError, match=rf"batch.mass_matrix: q: expected shape \(K, {nq}\).*got \({nq},\)"):
        b.mass_matrix(model, q[0])
    bad = x.copy()
    bad[4, 2] = np.inf
    with pytest.raises(ValueError, match=r"batch.inverse_dynamics: qdd\[4, 2\] = inf: expected a finite number"):
        b.inverse_dynamics(model, q, v, bad)
    with pytest.raises(ValueError, match="threads"):
        b.forward_dynamics_derivatives(model, q, v, x, threads=-1)
    with pytest.raises(TypeError, match="batch.forward_dynamics: tau: expected an array of numbers"):
        b.forward_dynamics(model, q, v, object())


# ---- rollout -----------------------------------------------------------------------------------

def initial_states(scene, K):
    return np.array([np.r_[scene.model.normalize(scene.q0 + 0.01 * k), scene.v0 + 0.01 * k] for k in range(K)])


@pytest.mark.parametrize("name, method", [("double_pendulum", "rk4"), ("driven_pendulum", "rk4"),
                                          ("tumbling_t_handle", "rk4"), ("double_pendulum", "semi-implicit-euler"),
                                          ("double_pendulum", "cvode-adams")])
def test_rollout_equals_simulate(name, method):
    scene = soadyn.load_scenario(f"{SCENARIOS}/{name}.yaml")
    y0 = initial_states(scene, 3)
    dt, T = (1e-2, 30) if method.startswith("cvode") else (1e-3, 100)
    states, energies = soadyn.rollout(scene, y0, steps=T, dt=dt, method=method, threads=2)
    assert states.shape == (3, T, scene.model.nq + scene.model.nv) and energies.shape == (3, T)
    nq = scene.model.nq
    for k in range(3):
        scene.q0, scene.v0 = y0[k, :nq], y0[k, nq:]
        traj = soadyn.simulate(scene, method, dt=dt, output_dt=dt, t_end=T * dt)
        ref = np.hstack([traj.q[1:], traj.v[1:]])
        assert np.abs(states[k] - ref).max() <= 1e-12 * max(1.0, np.abs(ref).max())
        assert np.abs(energies[k] - traj.total_energy[1:]).max() <= 1e-12 * max(1.0, np.abs(traj.total_energy).max())


def test_rollout_threads_controls_and_callback_agree():
    scene = soadyn.load_scenario(f"{SCENARIOS}/double_pendulum.yaml")
    K, T = 5, 60
    y0 = initial_states(scene, K)
    u = np.zeros((K, T, scene.model.nv))
    u[:, :, 1] = np.sin(0.1 * np.arange(T))[None, :] * np.arange(K)[:, None]
    one, e1 = soadyn.rollout(scene, y0, u, method="rk4", dt=1e-3, threads=1)
    for threads in (2, 3):
        many, e = soadyn.rollout(scene, y0, u, method="rk4", dt=1e-3, threads=threads)
        assert (many == one).all() and (e == e1).all()  # the same code on the same numbers
    seen = []

    def control(k, s, t, y):
        seen.append((k, s, t, y.shape))
        return u[k, s]

    by_callback, _ = soadyn.rollout(scene, y0, control, steps=T, method="rk4", dt=1e-3, threads=2)
    assert (by_callback == one).all()
    assert len(seen) == K * T and (0, 0, 0.0, (4,)) in seen
    # no control: a model alone, defaults rk4 at dt = 1e-3
    free, energy = soadyn.rollout(scene.model, y0, steps=3, energies=False)
    assert free.shape == (K, 3, 4) and energy is None


def test_rollout_bad_arguments_refused():
    scene = soadyn.load_scenario(f"{SCENARIOS}/double_pendulum.yaml")
    y0 = initial_states(scene, 2)
    with pytest.raises(ValueError, match=r"rollout: initial_states: expected shape \(K, 4\).*got \(2, 3\)"):
        soadyn.rollout(scene, y0[:, :3], steps=2)
    with pytest.raises(ValueError, match=r"rollout: controls: expected shape \(2, T, 2\).*got \(3, 5, 2\)"):
        soadyn.rollout(scene, y0, np.zeros((3, 5, 2)))
    with pytest.raises(ValueError, match=r"rollout: controls: expected shape \(2, 4, 2\)"):
        soadyn.rollout(scene, y0, np.zeros((2, 5, 2)), steps=4)
    u = np.zeros((2, 3, 2))
    u[1, 2, 0] = np.nan
    with pytest.raises(ValueError, match=r"rollout: controls\[1, 2, 0\] = nan: expected a finite number"):
        soadyn.rollout(scene, y0, u)
    y_bad = y0.copy()
    y_bad[0, 3] = np.inf
    with pytest.raises(ValueError, match=r"rollout: initial_states\[0, 3\] = inf"):
        soadyn.rollout(scene, y_bad, steps=2)
    with pytest.raises(ValueError, match="rollout: steps"):
        soadyn.rollout(scene, y0)
    with pytest.raises(ValueError, match="method: unknown method 'rk5'; did you mean 'rk4'"):
        soadyn.rollout(scene, y0, steps=2, method="rk5")
    with pytest.raises(ValueError, match=r"the callback must return 2 numbers \(nv,\), got \(3,\)"):
        soadyn.rollout(scene, y0, lambda k, s, t, y: np.zeros(3), steps=2)
    with pytest.raises(ZeroDivisionError):  # the callback's own exception comes through
        soadyn.rollout(scene, y0, lambda k, s, t, y: 1 / 0, steps=2, threads=2)
    with pytest.raises(TypeError, match="rollout: scene"):
        soadyn.rollout(3.0, y0, steps=2)


def test_rollout_failure_is_nan_and_a_warning():
    scene = soadyn.load_scenario(f"{SCENARIOS}/double_pendulum.yaml")
    y0 = initial_states(scene, 3)
    y0[1, 2:] = 1e5
    with pytest.warns(RuntimeWarning, match="1 of 3 rollouts failed.*rollout 1: unstable"):
        states, _ = soadyn.rollout(scene, y0, steps=400, method="euler", dt=0.05)
    assert np.isnan(states[1, -1]).all() and np.isfinite(states[[0, 2]]).all()


@pytest.mark.parametrize("threads", [1, 2])
def test_ctrl_c_ends_a_long_rollout(threads):
    scene = soadyn.load_scenario(f"{SCENARIOS}/double_pendulum.yaml")
    y0 = initial_states(scene, 2)

    def interrupt(signum, frame):
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGALRM, interrupt)
    try:
        signal.setitimer(signal.ITIMER_REAL, 0.2)
        start = time.monotonic()
        with pytest.raises(KeyboardInterrupt):
            soadyn.rollout(scene, y0, steps=300000, method="implicit-midpoint", dt=1e-4, threads=threads,
                           energies=False)
        took = time.monotonic() - start
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    assert took < 5.0, took  # the rollouts alone would take several seconds


def test_old_names_warn_and_give_the_same_results(rng):
    """bias, id_derivatives and fd_derivatives (module, batch and Pool) are kept one release: each
    warns DeprecationWarning naming the new name and returns what it did (fd_derivatives: two
    arrays with minv=False)"""
    model = soadyn.load(f"{SCENARIOS}/three_link_arm.yaml")
    data = model.create_data()
    K = 4
    q = rng.uniform(-1, 1, (K, model.nq))
    v, x = rng.uniform(-1, 1, (K, model.nv)), rng.uniform(-1, 1, (K, model.nv))
    pool = soadyn.batch.Pool(model)
    cases = [
        (lambda: soadyn.bias(model, data, q[0], v[0]), lambda: soadyn.bias_forces(model, data, q[0], v[0]), "bias_forces"),
        (lambda: soadyn.id_derivatives(model, data, q[0], v[0], x[0]),
         lambda: soadyn.inverse_dynamics_derivatives(model, data, q[0], v[0], x[0]), "inverse_dynamics_derivatives"),
        (lambda: soadyn.fd_derivatives(model, data, q[0], v[0], x[0]),
         lambda: soadyn.forward_dynamics_derivatives(model, data, q[0], v[0], x[0]), "forward_dynamics_derivatives"),
        (lambda: soadyn.batch.bias(model, q, v), lambda: soadyn.batch.bias_forces(model, q, v), "bias_forces"),
        (lambda: pool.id_derivatives(q, v, x), lambda: pool.inverse_dynamics_derivatives(q, v, x),
         "inverse_dynamics_derivatives"),
        (lambda: soadyn.batch.fd_derivatives(model, q, v, x), lambda: soadyn.batch.forward_dynamics_derivatives(model, q, v, x),
         "forward_dynamics_derivatives"),
        (lambda: pool.fd_derivatives(q, v, x, minv=False),
         lambda: pool.forward_dynamics_derivatives(q, v, x, minv=False)[:2], "forward_dynamics_derivatives"),
    ]
    for old, new, name in cases:
        with pytest.warns(DeprecationWarning, match=name):
            got = old()
        got = [np.array(a) for a in (got if isinstance(got, tuple) else (got,))]
        ref = new()
        ref = [np.array(a) for a in (ref if isinstance(ref, tuple) else (ref,))]
        assert len(got) == len(ref), name
        assert all(np.array_equal(a, b) for a, b in zip(got, ref)), name
