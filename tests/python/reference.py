"""Independent references for the free rigid rotor and the elliptic special functions.

Nothing here uses openmmrigid.  The rotor reference integrates the equations of motion
directly:

    Euler:    I1 dw1/dt = (I2 - I3) w2 w3   (and cyclic)          body-frame angular velocity
    attitude: dA/dt = -W(w) A,  W(w) = [[0,-w3,w2],[w3,0,-w1],[-w2,w1,0]],  v_body = A v_lab

with scipy's DOP853 at the tightest tolerance scipy accepts (rtol = 100 eps = 2.2e-14, the
requested 1e-14 is raised to it).  The equations are integrated in the scaled time
tau = |w(0)| t with the scaled velocity w/|w(0)| and the moments divided by their largest
value: Euler's equations are homogeneous of degree two in w and of degree zero in I, so the
scaled problem is the same for every |w(0)| (1e-8 ... 1e8) and every unit of moment.

Accuracy (checked in test_reference.py against the paper's Section 5 values, the closed-form
spherical and symmetric tops and the conservation laws): about 1e-12 relative over a few
rotation periods of a well-conditioned body.  Near the separatrix E = L^2 / (2 I2) the problem
itself is ill-conditioned (perturbations grow like exp(lambda t) on the approach to the
unstable middle axis), so the reference is only trusted for lambda t <= ~6 there
(see separatrix_growth_rate).

A body with one zero moment (linear rotor) is integrated with the angular-velocity component
along the zero-moment axis set to zero and its Euler equation dropped.
"""

from fractions import Fraction

import mpmath
import numpy as np
from scipy.integrate import solve_ivp

RTOL = 100 * np.finfo(float).eps  # scipy's floor for rtol; ~1e-14 as requested
ATOL = 1e-16                      # in the scaled variables (|w| = 1, |A_ij| <= 1)


def skew(w):
    """W(w), the matrix with W(w) v = w x v."""
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def rotation(x):
    """exp(W(x)): rotation by the angle |x| about x (Rodrigues), computed without cancellation."""
    x = np.asarray(x, dtype=float)
    angle = np.linalg.norm(x)
    if angle == 0.0:
        return np.eye(3)
    k = skew(x / angle)
    return np.eye(3) + np.sin(angle) * k + 2.0 * np.sin(angle / 2) ** 2 * (k @ k)


def random_rotation(rng):
    """A uniformly random proper rotation matrix (orthonormal to rounding, det +1)."""
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    a, b, c, d = q
    return np.array([
        [a * a + b * b - c * c - d * d, 2 * (b * c - a * d), 2 * (b * d + a * c)],
        [2 * (b * c + a * d), a * a - b * b + c * c - d * d, 2 * (c * d - a * b)],
        [2 * (b * d - a * c), 2 * (c * d + a * b), a * a - b * b - c * c + d * d],
    ])


def _rhs(moments, zero_axis):
    # Euler coefficients (I2 - I3)/I1 etc.; the zero-moment axis of a linear body has none.
    c = [0.0, 0.0, 0.0]
    for k, (a, b) in enumerate([(1, 2), (2, 0), (0, 1)]):
        if k != zero_axis:
            c[k] = float((moments[a] - moments[b]) / moments[k])
    c1, c2, c3 = c

    def rhs(_tau, y):
        # Written out on Python floats: twenty times faster than numpy on 12 numbers.
        w1, w2, w3, a11, a12, a13, a21, a22, a23, a31, a32, a33 = y.tolist()
        return np.array([
            c1 * w2 * w3, c2 * w3 * w1, c3 * w1 * w2,
            # -W(w) A
            w3 * a21 - w2 * a31, w3 * a22 - w2 * a32, w3 * a23 - w2 * a33,
            w1 * a31 - w3 * a11, w1 * a32 - w3 * a12, w1 * a33 - w3 * a13,
            w2 * a11 - w1 * a21, w2 * a12 - w1 * a22, w2 * a13 - w1 * a23,
        ])

    return rhs


def linear_axis(moments):
    """Index of the zero moment of a linear body, or None."""
    zeros = [k for k in range(3) if moments[k] == 0.0]
    return zeros[0] if len(zeros) == 1 else None


def integrate(moments, omega, attitude, times, rtol=RTOL, atol=ATOL):
    """Reference solution (omega(t), A(t)) at each t in `times` (any sign, any order).

    Returns arrays of shapes (n, 3) and (n, 3, 3).
    """
    moments = np.asarray(moments, dtype=float)
    omega = np.array(omega, dtype=float)
    attitude = np.asarray(attitude, dtype=float)
    times = np.atleast_1d(np.asarray(times, dtype=float))
    zero_axis = linear_axis(moments)
    if zero_axis is not None:
        omega[zero_axis] = 0.0
    scale = np.linalg.norm(omega)
    n = len(times)
    omegas = np.empty((n, 3))
    attitudes = np.empty((n, 3, 3))
    if scale == 0.0:
        omegas[:] = omega
        attitudes[:] = attitude
        return omegas, attitudes
    rhs = _rhs(moments / moments.max(), zero_axis)
    y0 = np.concatenate([omega / scale, attitude.ravel()])
    taus = times * scale
    for sign in (1.0, -1.0):
        select = (taus * sign > 0)
        if not select.any():
            continue
        order = np.argsort(taus[select] * sign)
        t_eval = taus[select][order]
        sol = solve_ivp(rhs, (0.0, t_eval[-1]), y0, method="DOP853", t_eval=t_eval,
                        rtol=rtol, atol=atol)
        if not sol.success:
            raise RuntimeError(f"reference integration failed: {sol.message}")
        idx = np.flatnonzero(select)[order]
        omegas[idx] = sol.y[:3].T * scale
        attitudes[idx] = sol.y[3:].T.reshape(-1, 3, 3)
    at_zero = taus == 0.0
    omegas[at_zero] = omega
    attitudes[at_zero] = attitude
    return omegas, attitudes


# --------------------------------------------------------------------------------------------
# Closed forms that need no integration (used to check the integrator and the rotor)

def steady_rotation(omega, attitude, t):
    """A(t) for constant omega (spherical top, or rotation about a principal axis)."""
    return rotation(-np.asarray(omega, dtype=float) * t) @ attitude


def symmetric_top(moments, omega, attitude, t, axis):
    """Closed-form symmetric top (unique moment on `axis`), textbook solution.

    The body-frame omega precesses about the symmetry axis with rate
    wp = (1 - I_axis / I_perp) w_axis, and A(t) = R_axis(-wp t) R(-L t / I_perp) A(0).
    """
    moments = np.asarray(moments, dtype=float)
    omega = np.asarray(omega, dtype=float)
    i_perp = moments[(axis + 1) % 3]
    wp = (1.0 - moments[axis] / i_perp) * omega[axis]
    e = np.zeros(3)
    e[axis] = 1.0
    turn = rotation(-wp * t * e)
    angular_momentum = moments * omega
    return turn @ omega, turn @ rotation(-angular_momentum * t / i_perp) @ attitude


# --------------------------------------------------------------------------------------------
# Exact invariants (rational arithmetic on the binary inputs)

def exact_invariants(moments, omega):
    """(2E, L^2) as Fractions, exactly for the given doubles."""
    i = [Fraction(float(x)) for x in moments]
    w = [Fraction(float(x)) for x in omega]
    two_e = sum(i[k] * w[k] ** 2 for k in range(3))
    l2 = sum((i[k] * w[k]) ** 2 for k in range(3))
    return two_e, l2


def exact_parameter(moments, omega):
    """The elliptic parameter m in [0, 1] of an asymmetric top, exactly, as a Fraction.

    m = (L^2 - 2E I3)(I1 - I2) / ((L^2 - 2E I1)(I3 - I2)) in the ordering (I1, I3) = (smallest,
    largest) or (largest, smallest), whichever gives m <= 1 (van Zon & Schofield eq. 3.32).
    """
    i = [Fraction(float(x)) for x in moments]
    two_e, l2 = exact_invariants(moments, omega)
    order = sorted(range(3), key=lambda k: i[k])
    small, middle, large = (i[k] for k in order)
    if l2 == two_e * middle:      # on the separatrix (or steady rotation about the middle axis)
        return Fraction(1)
    for i1, i3 in ((small, large), (large, small)):
        d3 = l2 - two_e * i3
        d1 = l2 - two_e * i1
        if d1 == 0:
            continue
        m = d3 * (i1 - middle) / (d1 * (i3 - middle))
        if 0 <= m <= 1:
            return m
    return Fraction(0)  # steady rotation about the smallest or largest axis


def separatrix_offset(moments, omega):
    """(L^2 - 2E I2) / L^2 exactly (as a float): 0 on the separatrix, sign gives the side."""
    i = sorted(float(x) for x in moments)
    two_e, l2 = exact_invariants(moments, omega)
    return float((l2 - two_e * Fraction(i[1])) / l2)


def separatrix_growth_rate(moments, omega):
    """The instability rate lambda of rotation about the middle axis at the body's |L|.

    Near the separatrix, errors in any solution grow like exp(lambda t).
    """
    i1, i2, i3 = sorted(float(x) for x in moments)
    _, l2 = exact_invariants(moments, omega)
    w = np.sqrt(float(l2)) / i2
    return w * np.sqrt((i2 - i1) * (i3 - i2) / (i1 * i3))


def near_separatrix_omega(moments, omega, offset):
    """omega changed so that (L^2 - 2E I2) / L^2 = offset (0: on the separatrix, to rounding).

    The component along the axis of the largest moment is solved for; the others are kept.
    Returns the new omega (to rounding; check with separatrix_offset).
    """
    moments = np.asarray(moments, dtype=float)
    omega = np.array(omega, dtype=float)
    order = np.argsort(moments)
    a, b, c = order
    ia, ib, ic = moments[a], moments[b], moments[c]
    wa, wb = omega[a], omega[b]
    # L^2 - 2E Ib = Ia wa^2 (Ia - Ib) + Ic wc^2 (Ic - Ib) = offset (Ia^2 wa^2 + Ib^2 wb^2 + Ic^2 wc^2)
    numerator = offset * (ia**2 * wa**2 + ib**2 * wb**2) + ia * wa**2 * (ib - ia)
    denominator = ic * (ic - ib) - offset * ic**2
    wc2 = numerator / denominator
    if wc2 < 0:
        raise ValueError("offset not reachable by changing the largest-axis component")
    omega[c] = np.copysign(np.sqrt(wc2), omega[c] if omega[c] != 0 else 1.0)
    return omega


# --------------------------------------------------------------------------------------------
# Textbook closed form of omega(t) in high precision (Landau & Lifshitz, Mechanics, sec. 37;
# the sign conventions of van Zon & Schofield sec. 3.3).  Independent of the ODE above and of
# openmmrigid; used for long times, where the ODE's error grows.

def omega_closed_form(moments, omega, t, dps=40):
    """omega(t) of an asymmetric top (three distinct moments, omega off every principal axis),
    evaluated with mpmath at `dps` digits on the exact binary inputs.  Returns a float array."""
    with mpmath.workdps(dps):
        moments = [mpmath.mpf(float(x)) for x in moments]
        omega = [mpmath.mpf(float(x)) for x in omega]
        t = mpmath.mpf(float(t))
        # A cyclic shift (a proper rotation, under which Euler's equations are invariant) puts
        # the middle moment in slot 1.
        middle = sorted(range(3), key=lambda k: moments[k])[1]
        shift = [(j + middle - 1) % 3 for j in range(3)]
        ix, iy, iz = (moments[k] for k in shift)
        wx, wy, wz = (omega[k] for k in shift)
        l2 = (ix * wx) ** 2 + (iy * wy) ** 2 + (iz * wz) ** 2
        two_e = ix * wx ** 2 + iy * wy ** 2 + iz * wz ** 2
        # eq. (3.32): order so that 0 <= m <= 1; U* = [[0,0,1],[0,-1,0],[1,0,0]]
        flip = (two_e > l2 / iy and ix < iz) or (two_e < l2 / iy and ix > iz)
        if flip:
            i1, i2, i3, w1, w2, w3 = iz, iy, ix, wz, -wy, wx
        else:
            i1, i2, i3, w1, w2, w3 = ix, iy, iz, wx, wy, wz
        d3 = i1 * w1 ** 2 * (i1 - i3) + i2 * w2 ** 2 * (i2 - i3)      # L^2 - 2E I3
        d1 = i2 * w2 ** 2 * (i2 - i1) + i3 * w3 ** 2 * (i3 - i1)      # L^2 - 2E I1
        s1 = mpmath.sign(w1)
        s3 = mpmath.sign(w3)
        w1m = s1 * mpmath.sqrt(d3 / (i1 * (i1 - i3)))
        w2m = -s1 * mpmath.sqrt(d3 / (i2 * (i2 - i3)))
        w3m = s3 * mpmath.sqrt(d1 / (i3 * (i3 - i1)))
        wp = mpmath.sign(i2 - i3) * s3 * mpmath.sqrt(d1 * (i3 - i2) / (i1 * i2 * i3))
        m = d3 * (i1 - i2) / (d1 * (i3 - i2))
        x = max(-1, min(1, w2 / w2m))
        u = wp * t + mpmath.ellipf(mpmath.asin(x), m)
        sn, cn, dn = (mpmath.ellipfun(name, u, m=m) for name in ("sn", "cn", "dn"))
        w1, w2, w3 = w1m * cn, w2m * sn, w3m * dn
        shifted = [w3, -w2, w1] if flip else [w1, w2, w3]
        result = np.empty(3)
        for j in range(3):
            result[shift[j]] = float(shifted[j])
        return result
