"""The gyro fit from hand rotations between static poses, (F.3)–(F.10).

A synthetic hand session with known truth: a chain of static poses (attitudes C_k, body to
level); between two poses the body turns about a body-fixed axis (a "gravity" rotation to the
next pose, or a whole turn about the vertical), with a smooth minimum-jerk angle profile
φ(t) = φ_T·(10τ³ − 15τ⁴ + 6τ⁵), so its rate is analytic at any time; the gyro samples it at
`fs` through y = b + (I + M)·ω + white noise of density N; each static pose gives a gyro mean
over `static_s` (the bias of a rotation is the mean of its two) and an accelerometer mean
through the inverse of (F.1) with white errors of σ_a.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from imucalib.errors import InsufficientExcitationError, InvalidInputError
from imucalib.estimation import gyro_rotations as gr
from imucalib.estimation.gravity_norm import fit_gravity_norm
from imucalib.estimation.gyro_rotations import (
    PARAMETERS,
    RotationObservation,
    fit_gyro_rotations,
    fit_turns_linear,
)

G = 9.80665
DEG = np.pi / 180
#: A consumer gyro: 1–2 % scale, a few mrad of non-orthogonality and misalignment.
M_TRUE = np.array([[0.012, 0.004, -0.006],
                   [-0.003, -0.015, 0.005],
                   [0.007, -0.002, 0.009]])
B_TRUE = np.array([0.02, -0.03, 0.015])              # rad/s
#: The accelerometer θ of (F.1): b, s, α.
THETA_A = np.array([0.05, -0.03, 0.04, 3e-3, -2e-3, 1e-3, 2e-3, -1.5e-3, 1e-3])
N_CONSUMER = 0.01 * DEG                               # rad/s/√Hz
SIGMA_A = 150e-6 * G / np.sqrt(5.0)                   # 150 µg/√Hz over 5 s [m/s²]


def _raw_accel(f):
    """The inverse of (F.1) under THETA_A: y = (I + diag s)⁻¹·T⁻¹·f + b."""
    p = THETA_A
    t = np.array([[1.0, -p[6], p[7]], [0.0, 1.0, -p[8]], [0.0, 0.0, 1.0]])
    return np.linalg.solve(t, f) / (1.0 + p[3:6]) + p[:3]


@dataclass
class Session:
    """Settings of a synthetic session."""

    fs: float = 200.0
    density: float = N_CONSUMER
    sigma_a: float = SIGMA_A
    static_s: float = 5.0
    m_true: np.ndarray = field(default_factory=lambda: M_TRUE.copy())
    noise: bool = True
    g_sens: np.ndarray | None = None          # rad/s per m/s², not fitted (misfit test)


def _motion(rotvec, duration, fs, margin=0.2):
    """Times, angle fractions and body rates of a min-jerk rotation by `rotvec` about a
    body-fixed axis, still for `margin` seconds at either end."""
    t = np.arange(0.0, duration + 2 * margin + 0.5 / fs, 1.0 / fs)
    tau = np.clip((t - margin) / duration, 0.0, 1.0)
    frac = tau**3 * (10 - 15 * tau + 6 * tau**2)
    sdot = 30 * tau**2 * (1 - tau) ** 2 / duration
    return t, frac, sdot[:, None] * np.asarray(rotvec)[None, :]


@dataclass
class Clean:
    """A noise-free session: the poses' forces and raw means, the motions' samples."""

    force: list = field(default_factory=list)        # body specific force of each pose
    accel: list = field(default_factory=list)        # raw accelerometer mean of each pose
    motions: list = field(default_factory=list)      # (kind, time_s, gyro_rps, angle_rad)


def _clean(plan, s: Session, start=(0.0, 0.0, 0.0)) -> Clean:
    """The noise-free session of a plan of ("gravity", rotvec, duration) and ("turn", ±1,
    duration) steps (a turn: about the body's vertical, a whole turn), from the pose
    `start` (a rotation vector from level)."""
    c = Rotation.from_rotvec(start)
    out = Clean()

    def pose(att):
        f = att.inv().apply([0.0, 0.0, G])           # body coordinates of the specific force
        out.force.append(f)
        out.accel.append(_raw_accel(f))

    pose(c)
    for kind, arg, duration in plan:
        if kind == "gravity":
            rotvec = np.asarray(arg, dtype=float)
        else:
            rotvec = arg * 2 * np.pi * c.inv().apply([0.0, 0.0, 1.0])
        t, frac, w = _motion(rotvec, duration, s.fs)
        c = c * Rotation.from_rotvec(rotvec)
        pose(c)
        y = B_TRUE + w @ (np.eye(3) + s.m_true).T
        if s.g_sens is not None:                     # a g-sensitive gyro (not in the model)
            f_t = Rotation.from_rotvec(frac[:, None] * rotvec).inv().apply(out.force[-2])
            y = y + f_t @ s.g_sens.T
        out.motions.append((kind, t, y, 2 * np.pi * abs(arg) if kind == "turn" else None))
    return out


def _draw(clean: Clean, rng, s: Session, noise: bool = True):
    """The rotations of one draw of the noise of a clean session."""
    n = len(clean.accel)
    sg = s.density / np.sqrt(s.static_s)             # σ of a static gyro mean
    accel = np.array(clean.accel) + (rng.normal(0.0, s.sigma_a, (n, 3)) if noise else 0.0)
    static = B_TRUE + (rng.normal(0.0, sg, (n, 3)) if noise else np.zeros((n, 3)))
    if s.g_sens is not None:
        static = static + np.array(clean.force) @ s.g_sens.T
    out = []
    for k, (kind, t, y, angle) in enumerate(clean.motions):
        if noise:
            y = y + rng.normal(0.0, s.density * np.sqrt(s.fs), y.shape)
        out.append(RotationObservation(
            kind=kind, time_s=t, gyro_rps=y, bias_rps=0.5 * (static[k] + static[k + 1]),
            bias_std_rps=np.full(3, sg / np.sqrt(2.0)),
            accel_before_mps2=accel[k], accel_before_std=np.full(3, s.sigma_a),
            accel_after_mps2=accel[k + 1], accel_after_std=np.full(3, s.sigma_a),
            angle_rad=angle))
    return out


def _session(rng, plan, s: Session, start=(0.0, 0.0, 0.0)):
    return _draw(_clean(plan, s, start), rng, s, noise=s.noise)


# Plans: hand rotations of 90° about each body axis in turn, some oblique; turns with each
# axis up; a mix.
def _gravity_plan(grav_s=2.0):
    steps = []
    for axis in ([1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 0], [0, 1, -1], [1, 0, 1]):
        for sign in (1, -1):
            v = np.asarray(axis, dtype=float)
            steps.append(("gravity", sign * np.pi / 2 * v / np.linalg.norm(v), grav_s))
    return steps


def _turn_plan(turn_s=4.0, grav_s=2.0):
    """Two turns (one each way) with z up, then y up (90° about x), then x up (90° about z)."""
    return [("turn", 1, turn_s), ("turn", -1, turn_s),
            ("gravity", [np.pi / 2, 0.0, 0.0], grav_s), ("turn", 1, turn_s),
            ("turn", -1, turn_s), ("gravity", [0.0, 0.0, np.pi / 2], grav_s),
            ("turn", 1, turn_s), ("turn", -1, turn_s)]


def _turns_only(rots):
    return [r for r in rots if r.kind == "turn"]


def _mixed_plan(turn_s=4.0, grav_s=2.0):
    return [*_gravity_plan(grav_s)[:8], ("turn", 1, turn_s),
            ("gravity", [np.pi / 2, 0.0, 0.0], grav_s), ("turn", -1, turn_s),
            ("gravity", [0.0, 0.0, np.pi / 2], grav_s), ("turn", 1, turn_s)]


def _fit(rots, s: Session, **kw):
    return fit_gyro_rotations(rots, THETA_A, gyro_noise_density_rps_rthz=s.density, **kw)


def _accel_covariance(rng):
    """C_a of a gravity-norm fit of 14 random poses with 5 s means (the design's bound)."""
    f = Rotation.random(14, random_state=rng).apply([0.0, 0.0, G])
    y = np.array([_raw_accel(v) for v in f])
    sy = np.full_like(y, SIGMA_A)
    return fit_gravity_norm(y + rng.normal(0.0, sy), sy, G).covariance_noise


@pytest.mark.parametrize("design", ["gravity", "turns", "mixed"])
def test_noise_free_rotations_give_the_truth(design):
    s = Session(noise=False)
    plan = {"gravity": _gravity_plan(), "turns": _turn_plan(), "mixed": _mixed_plan()}[design]
    rots = _session(np.random.default_rng(0), plan, s)
    if design == "turns":
        rots = _turns_only(rots)
    fit = _fit(rots, s)
    np.testing.assert_allclose(fit.values, M_TRUE.ravel(), atol=1e-6)
    np.testing.assert_allclose(fit.matrix(), M_TRUE, atol=1e-6)
    assert fit.quality.chi2 < 1e-6 and fit.iterations < 10
    assert all(np.max(np.abs(r)) < 1e-8 for r in fit.residuals)
    assert [r.size for r in fit.residuals] == [3 if o.kind == "turn" else 2 for o in rots]
    assert PARAMETERS[1] == "gyro_M_xy" and len(PARAMETERS) == 9


def test_gauss_newton_on_turns_is_the_closed_form():
    s = Session(fs=100.0)
    rots = _turns_only(_session(np.random.default_rng(1), _turn_plan(3.0, 1.5), s))
    gn = _fit(rots, s)
    lin = fit_turns_linear(rots, THETA_A, gyro_noise_density_rps_rthz=s.density)
    assert lin.iterations == 0
    np.testing.assert_allclose(gn.values, lin.values, rtol=0, atol=1e-12)
    np.testing.assert_allclose(gn.covariance, lin.covariance, rtol=1e-9)
    assert np.all(np.abs(gn.values - M_TRUE.ravel()) < 4 * gn.std())
    with pytest.raises(InvalidInputError, match="turns only"):
        fit_turns_linear(_session(np.random.default_rng(1), _mixed_plan(), s), THETA_A,
                         gyro_noise_density_rps_rthz=s.density)


def test_the_jacobian_is_the_derivative_of_the_residuals():
    s = Session(fs=100.0)
    rots = _session(np.random.default_rng(2), _mixed_plan(3.0, 1.5), s)
    design = gr._prepare(rots, THETA_A, s.density)
    m = 0.5 * M_TRUE.ravel()
    _, jac, _, _ = design.evaluate(m)
    num = np.zeros_like(jac)
    for p in range(9):
        h = np.eye(9)[p] * 1e-6
        plus = design.residuals(m + h, design.attitudes(m + h)[1][:, -1])
        minus = design.residuals(m - h, design.attitudes(m - h)[1][:, -1])
        num[:, p] = (plus - minus) / 2e-6
    # (F.9) is the continuous derivative; the discrete (F.4) differs by O(Δt²·ω²)
    assert np.max(np.abs(jac - num)) < 1e-3 * np.max(np.abs(num))


def test_a_motion_off_one_axis_is_integrated_to_second_order():
    """A rotation about x then about y inside one motion (0.9 and 1.2 rad in 1 s): (F.4) is
    not exact; its error falls with Δt² (200 Hz: a quarter of 100 Hz's 6e-5 rad)."""
    errors = []
    for fs in (100.0, 200.0):
        s = Session(fs=fs, noise=False)
        rots = _session(np.random.default_rng(0), _gravity_plan(1.0), s)
        # replace the rates of rotation 0 by a two-axis motion with the same end attitude
        t, frac, _ = _motion([1.0, 0.0, 0.0], 1.0, fs)
        b = 1.2 * frac                                        # angles 0.9·frac about x, then y
        tau = np.clip((t - 0.2) / 1.0, 0.0, 1.0)
        dadt = 0.9 * 30 * tau**2 * (1 - tau) ** 2
        dbdt = 1.2 * 30 * tau**2 * (1 - tau) ** 2
        ry = Rotation.from_rotvec(b[:, None] * [0.0, 1.0, 0.0])
        w = ry.inv().apply(dadt[:, None] * [1.0, 0.0, 0.0]) + dbdt[:, None] * [0.0, 1.0, 0.0]
        end = Rotation.from_rotvec([0.9, 0.0, 0.0]) * Rotation.from_rotvec([0.0, 1.2, 0.0])
        f0 = np.array([0.0, 0.0, G])
        r0 = rots[0]
        rots[0] = RotationObservation(
            kind="gravity", time_s=t, gyro_rps=B_TRUE + w @ (np.eye(3) + M_TRUE).T,
            bias_rps=r0.bias_rps, bias_std_rps=r0.bias_std_rps,
            accel_before_mps2=_raw_accel(f0), accel_before_std=r0.accel_before_std,
            accel_after_mps2=_raw_accel(end.inv().apply(f0)),
            accel_after_std=r0.accel_after_std)
        design = gr._prepare(rots[:1] * 3, THETA_A, s.density)
        errors.append(np.max(np.abs(design.residuals(
            M_TRUE.ravel(), design.attitudes(M_TRUE.ravel())[1][:, -1]))))
    assert 1e-5 < errors[0] < 1e-4
    assert 3.0 < errors[0] / errors[1] < 5.0


@pytest.mark.slow
def test_sigma_matches_the_monte_carlo_spread_of_a_consumer_session():
    s = Session(fs=100.0)
    clean = _clean(_mixed_plan(3.0, 1.5), s)
    rng = np.random.default_rng(3)
    fits = [_fit(_draw(clean, rng, s), s, tol=1e-8) for _ in range(300)]
    values = np.array([f.values for f in fits])
    sigma = np.mean([np.sqrt(np.diag(f.covariance_noise)) for f in fits], axis=0)
    ratio = values.std(axis=0, ddof=1) / sigma
    assert np.all(np.abs(ratio - 1.0) < 0.15), ratio
    assert np.all(np.abs(values.mean(axis=0) - M_TRUE.ravel()) < 4 * sigma / np.sqrt(300))
    flagged = np.mean([f.quality.misfit for f in fits])
    assert flagged < 0.04
    assert 0.85 < np.mean([f.quality.reduced_chi2 for f in fits]) < 1.15
    # a consumer session: every entry to better than 0.01 % … 0.02 % (1e-4 … 2e-4)
    assert np.all(sigma < 2e-4)


@pytest.mark.slow
def test_the_accelerometer_error_is_carried_only_with_its_covariance():
    rng = np.random.default_rng(5)
    ca = _accel_covariance(rng)
    s = Session(fs=100.0)
    clean = _clean(_mixed_plan(3.0, 1.5), s)
    values, noise_only, total = [], [], []
    for _ in range(300):
        theta = rng.multivariate_normal(THETA_A, ca)
        fit = fit_gyro_rotations(_draw(clean, rng, s), theta, accel_covariance=ca,
                                 gyro_noise_density_rps_rthz=s.density, tol=1e-8)
        values.append(fit.values)
        noise_only.append(np.sqrt(np.diag(fit.covariance_noise)))
        total.append(fit.std())
    spread = np.std(values, axis=0, ddof=1)
    assert np.all(np.abs(spread / np.mean(total, axis=0) - 1.0) < 0.15)
    assert np.max(spread / np.mean(noise_only, axis=0)) > 1.5     # noise alone understates
    assert fit.cross_covariance is not None and fit.accel_sensitivity is not None
    np.testing.assert_allclose(fit.cross_covariance, fit.accel_sensitivity @ ca)
    assert fit.covariance_accel is not None
    assert np.min(np.linalg.eigvalsh(fit.covariance_accel)) > -1e-9 * np.max(
        np.diag(fit.covariance_accel))                       # the accelerometer only adds
    np.testing.assert_allclose(fit.covariance, (fit.covariance_noise + fit.covariance_accel)
                               * fit.quality.sigma_scale**2, rtol=1e-9, atol=1e-18)


def test_a_g_sensitive_gyro_is_flagged_and_the_scaled_sigma_cover_the_error():
    g_sens = 3e-4 * np.array([[1.0, 0.3, -0.5], [0.2, -1.0, 0.4], [-0.6, 0.5, 1.0]])
    s = Session(fs=100.0, g_sens=g_sens)
    clean = _clean(_mixed_plan(3.0, 1.5), s)
    for seed in range(3):
        fit = _fit(_draw(clean, np.random.default_rng(seed), s), s)
        assert fit.quality.misfit and fit.quality.reduced_chi2 > 3
        err = np.abs(fit.values - M_TRUE.ravel())
        assert np.all(err < 4 * fit.std())
        np.testing.assert_allclose(fit.std(), np.sqrt(np.diag(fit.covariance_noise))
                                   * fit.quality.birge_ratio)


@pytest.mark.parametrize(("plan", "start", "unseen"), [
    ([("turn", 1, 3.0), ("turn", -1, 3.0), ("turn", 1, 3.0)], (0.0, 0.0, 0.0),
     {"gyro_M_xx", "gyro_M_yx", "gyro_M_zx", "gyro_M_xy", "gyro_M_yy", "gyro_M_zy"}),
    ([("gravity", [0.0, 0.0, a], 1.5) for a in (np.pi / 2, -np.pi / 2, np.pi, np.pi / 2)],
     (np.pi / 2, 0.0, 0.0),
     {"gyro_M_xx", "gyro_M_yx", "gyro_M_zx", "gyro_M_xy", "gyro_M_yy", "gyro_M_zy"}),
    ([("gravity", [0.0, 0.0, a], 1.5) for a in (np.pi / 2, -np.pi / 2, np.pi, np.pi / 2)],
     (0.0, 0.0, 0.0),
     {"gyro_M_xx", "gyro_M_yx", "gyro_M_zx", "gyro_M_xy", "gyro_M_yy", "gyro_M_zy",
      "gyro_M_zz"}),
], ids=["turns-about-z", "rotations-about-horizontal-z", "rotations-about-vertical-z"])
def test_a_rank_deficient_design_names_what_it_cannot_see(plan, start, unseen):
    s = Session(fs=100.0)
    rots = _session(np.random.default_rng(0), plan, s, start=start)
    with pytest.raises(InsufficientExcitationError, match="do not excite") as info:
        _fit(rots, s)
    assert set(info.value.unobservable) == unseen


def _one(**changes):
    s = Session(fs=100.0, noise=False)
    base = _session(np.random.default_rng(0), [("turn", 1, 1.0)], s)[0]
    kw = {f: getattr(base, f) for f in ("kind", "time_s", "gyro_rps", "bias_rps",
                                        "bias_std_rps", "accel_before_mps2",
                                        "accel_before_std", "accel_after_mps2",
                                        "accel_after_std", "angle_rad")}
    kw.update(changes)
    return RotationObservation(**kw)


@pytest.mark.parametrize(("changes", "message"), [
    ({"kind": "spin"}, r"`kind` must be one of \['gravity', 'turn'\]; got 'spin'"),
    ({"gyro_rps": np.zeros((5, 3))}, r"`gyro_rps` must have shape \(\d+, 3\); got \(5, 3\)"),
    ({"time_s": np.r_[0.0, 0.01, 0.01, np.arange(3, 141) * 0.01]},
     "`time_s` must be strictly increasing"),
    ({"bias_rps": [0.0, np.nan, 0.0]}, "`bias_rps` must be finite; got 1 NaN"),
    ({"accel_after_mps2": [1.0, 2.0]}, r"`accel_after_mps2` must have shape \(3\)"),
    ({"accel_before_std": [0.0, 1e-3, 1e-3]}, "`accel_before_std` must be > 0"),
    ({"angle_rad": None}, "a \"turn\" needs `angle_rad`"),
    ({"angle_rad": 0.0}, "a \"turn\" needs `angle_rad`"),
])
def test_a_bad_rotation_is_refused_naming_what_was_expected(changes, message):
    with pytest.raises(InvalidInputError, match=message):
        _one(**changes)


def test_bad_fit_inputs_are_refused():
    rot = _one()
    with pytest.raises(InvalidInputError, match="at least 3 rotations; got 2"):
        fit_gyro_rotations([rot, rot], THETA_A, gyro_noise_density_rps_rthz=N_CONSUMER)
    with pytest.raises(InvalidInputError, match="must be a RotationObservation"):
        fit_gyro_rotations([rot, rot, "x"], THETA_A, gyro_noise_density_rps_rthz=N_CONSUMER)
    with pytest.raises(InvalidInputError,
                       match=r"`accel_theta` must hold the 9 values .*got shape \(6,\)"):
        fit_gyro_rotations([rot] * 3, THETA_A[:6], gyro_noise_density_rps_rthz=N_CONSUMER)
    tipped = _one(accel_after_mps2=_raw_accel(np.array([G, 0.0, 0.0])))
    with pytest.raises(InvalidInputError, match=r"rotation 0's poses are 90\.0° apart"):
        fit_gyro_rotations([tipped, rot, rot], THETA_A, gyro_noise_density_rps_rthz=N_CONSUMER)
    with pytest.raises(InvalidInputError, match="one or three values > 0"):
        fit_gyro_rotations([rot] * 3, THETA_A, gyro_noise_density_rps_rthz=-1.0)
