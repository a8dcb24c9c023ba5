"""Accuracy of openmmrigid.special against mpmath, grouped by regime, each with its own budget.

Conventions: parameter m (not the modulus k); m1 = 1 - m is passed explicitly near m = 1, and the
mpmath value is computed for m = 1 - m1 exactly (with 35 + log10(1/m1) digits: 1 - m1 needs ~106
bits when m1 ~ 1e-16); elsewhere mpmath works at 30 digits on the exact binary inputs.

Error measures:
- integrals (K, F, Pi, R_F, R_J): relative error |f - ref| / |ref|;
- Jacobi functions: |f - ref| / (|ref| + |u f'(u)|), i.e. relative error, except where the
  function is near a zero and a relative perturbation of u of the same size would move it more:
  an error that rounding of u (and, for large |u|, the reduction of u modulo 4K, which is
  inherently ~|u| eps) cannot avoid. f' = cn dn, -sn dn, -m sn cn.
"""

import zlib

import mpmath
import numpy as np
import openmm
import pytest

from openmmrigid import special

mpmath.mp.dps = 30
EPS = np.finfo(float).eps


def rng_for(name):
    return np.random.default_rng(zlib.crc32(name.encode()))


def log_uniform(rng, low, high, size):
    return 10.0 ** rng.uniform(np.log10(low), np.log10(high), size)


def mp_parameter(m, m1):
    """The exact mpmath parameter: 1 - m1 if m1 was given, else m."""
    if m1 is None:
        return mpmath.mpf(m)
    exact = mpmath.mpf(1) - mpmath.mpf(m1)
    assert mpmath.mpf(1) - exact == mpmath.mpf(m1), "1 - m1 not exact at this precision"
    return exact


def parameter_samples(regime, rng, count):
    """(m, m1) pairs: m1 None means the function computes 1 - m itself."""
    if regime == "generic":
        return [(m, None) for m in rng.uniform(0.1, 0.9, count)]
    if regime == "m-near-0":
        return [(m, None) for m in log_uniform(rng, 1e-16, 1e-3, count)]
    if regime == "m-near-1":
        return [(1.0 - m1, m1) for m1 in log_uniform(rng, 1e-16, 1e-3, count)]
    if regime == "m-extremely-near-1":
        return [(1.0 - m1, m1) for m1 in log_uniform(rng, 1e-300, 1e-16, count)]
    raise ValueError(regime)


def precision_for(m1):
    """Enough digits that 1 - m1 is exact and 30 digits remain beyond it."""
    if m1 is None or m1 == 0:
        return mpmath.workdps(mpmath.mp.dps)
    return mpmath.workdps(35 + max(0, int(np.ceil(-np.log10(m1)))))


def worst(errors):
    """(largest error, its input) from a list of (error, input)."""
    return max(errors, key=lambda item: item[0])


# ============================================================================================
# Jacobi elliptic functions

def jacobi_errors(samples):
    """Mixed errors of sn, cn, dn at (u, m, m1) samples: a list of (error, (u, m, m1, name))."""
    errors = []
    for u, m, m1 in samples:
        got = special.jacobiElliptic(u, m, m1) if m1 is not None else \
            special.jacobiElliptic(u, m)
        assert len(got) == 3
        with precision_for(m1):
            mm = mp_parameter(m, m1)
            uu = mpmath.mpf(u)
            sn, cn, dn = (mpmath.ellipfun(name, uu, m=mm) for name in ("sn", "cn", "dn"))
            derivatives = (cn * dn, -sn * dn, -mm * sn * cn)
            for name, value, want, slope in zip(("sn", "cn", "dn"), got, (sn, cn, dn),
                                                derivatives):
                scale = abs(want) + abs(uu * slope)
                error = float(abs(mpmath.mpf(value) - want) / scale) if scale else \
                    float(abs(mpmath.mpf(value)))
                if not np.isfinite(value):
                    error = np.inf
                errors.append((error, (u, m, m1, name, value, float(want))))
    return errors


def jacobi_samples(regime, count=40, turns=(-2.0, 2.0)):
    rng = rng_for("jacobi" + regime + str(turns))
    samples = []
    for m, m1 in parameter_samples(regime, rng, count):
        with precision_for(m1):
            quarter = float(mpmath.ellipk(mp_parameter(m, m1)))
        samples.append((rng.uniform(min(turns), max(turns)) * quarter, m, m1))
    return samples


JACOBI_BUDGETS = {
    "generic": 2e-15,
    "m-near-0": 2e-15,
    "m-near-1": 1e-13,
    "m-extremely-near-1": 1e-13,
}


@pytest.mark.parametrize("regime", sorted(JACOBI_BUDGETS))
def test_jacobi_elliptic(regime):
    error, where = worst(jacobi_errors(jacobi_samples(regime)))
    assert error <= JACOBI_BUDGETS[regime], f"error {error:.3g} at (u, m, m1, f, got, want) = {where!r}"


LARGE_ARGUMENT_BUDGET = 1e-15  # |f - ref| <= 1e-15 |u f'| (+ 1e-15 |ref|)


@pytest.mark.parametrize("regime", ["generic", "m-near-0", "m-near-1"])
def test_jacobi_elliptic_large_argument(regime):
    """|u| from 10 K to 1e3 K: the reduction modulo 4K costs ~|u| eps, inherently."""
    samples = []
    for sign in (1.0, -1.0):
        samples += jacobi_samples(regime, count=20, turns=(10.0 * sign, 1e3 * sign))
    error, where = worst(jacobi_errors(samples))
    assert error <= LARGE_ARGUMENT_BUDGET, f"error {error:.3g} at (u, m, m1, f, got, want) = {where!r}"


def test_jacobi_elliptic_small_argument():
    rng = rng_for("jacobi small argument")
    samples = [(u * s, m, None) for u, s, m in zip(log_uniform(rng, 1e-300, 1e-2, 40),
                                                    rng.choice([-1.0, 1.0], 40),
                                                    rng.uniform(0.0, 1.0, 40))]
    error, where = worst(jacobi_errors(samples))
    assert error <= 1e-15, f"error {error:.3g} at (u, m, m1, f, got, want) = {where!r}"


@pytest.mark.parametrize("u", [0.0, 1e-8, 0.5, -1.3, 2.0, 7.1, -30.0, 1e3])
def test_jacobi_elliptic_m_equals_0(u):
    error, where = worst(jacobi_errors([(u, 0.0, None), (u, 0.0, 1.0)]))
    assert error <= 1e-15, f"error {error:.3g} at (u, m, m1, f, got, want) = {where!r}"
    sn, cn, dn = special.jacobiElliptic(u, 0.0)
    assert dn == 1.0
    assert abs(sn - np.sin(u)) <= 2 * EPS * (abs(np.sin(u)) + abs(u * np.cos(u)))
    assert abs(cn - np.cos(u)) <= 2 * EPS * (abs(np.cos(u)) + abs(u * np.sin(u)))


@pytest.mark.parametrize("u", [0.0, 1e-8, 0.5, -1.3, 2.0, 7.1, -30.0, 300.0])
def test_jacobi_elliptic_m_equals_1(u):
    for got in (special.jacobiElliptic(u, 1.0), special.jacobiElliptic(u, 1.0, 0.0)):
        want = (np.tanh(u), 1 / np.cosh(u), 1 / np.cosh(u))
        for value, expected in zip(got, want):
            # tanh, sech: relative error, allowing for the slope as above
            assert abs(value - expected) <= 4 * EPS * (abs(expected) + abs(u) * abs(expected)), \
                f"u={u}: got {got}, want {want}"


def test_jacobi_elliptic_at_zero_is_exact():
    for m, m1 in [(0.0, 1.0), (0.3, 0.7), (1.0 - 1e-12, 1e-12), (1.0, 0.0)]:
        assert tuple(special.jacobiElliptic(0.0, m, m1)) == (0.0, 1.0, 1.0)


# ============================================================================================
# Identities

IDENTITY_SAMPLES = (jacobi_samples("generic", 30) + jacobi_samples("m-near-0", 15)
                    + jacobi_samples("m-near-1", 30)
                    + jacobi_samples("generic", 15, turns=(-1e3, 1e3)))


@pytest.mark.parametrize("index", range(len(IDENTITY_SAMPLES)))
def test_pythagorean_identities(index):
    u, m, m1 = IDENTITY_SAMPLES[index]
    sn, cn, dn = special.jacobiElliptic(u, m, m1)
    assert abs(sn * sn + cn * cn - 1) <= 1e-15, (u, m, m1)
    assert abs(dn * dn + m * sn * sn - 1) <= 1e-15, (u, m, m1)
    assert -1 <= sn <= 1 and -1 <= cn <= 1 and 0 < dn <= 1


@pytest.mark.parametrize("index", range(len(IDENTITY_SAMPLES)))
def test_periodicity(index):
    u, m, m1 = IDENTITY_SAMPLES[index]
    quarter = special.ellipticK(m, m1)
    sn, cn, dn = special.jacobiElliptic(u, m, m1)
    full = special.jacobiElliptic(u + 4 * quarter, m, m1)
    half = special.jacobiElliptic(u + 2 * quarter, m, m1)
    # u + 4K is rounded and K carries its own rounding: a shift of u by ~eps (|u| + 4K)
    tolerance = 4 * EPS * (abs(u) + 4 * quarter) + 4 * EPS
    assert abs(full[0] - sn) <= tolerance, (u, m, m1)
    assert abs(full[1] - cn) <= tolerance, (u, m, m1)
    assert abs(full[2] - dn) <= tolerance, (u, m, m1)
    assert abs(half[0] + sn) <= tolerance, (u, m, m1)
    assert abs(half[1] + cn) <= tolerance, (u, m, m1)
    assert abs(half[2] - dn) <= tolerance, (u, m, m1)


@pytest.mark.parametrize("regime", ["generic", "m-near-0", "m-near-1"])
def test_ellipticF_inverts_sn(regime):
    """F(sn(u)|m) = u for |u| <= K, to within the conditioning sn / (cn dn) of the inversion."""
    samples = jacobi_samples(regime, 40, turns=(-1.0, 1.0))
    for u, m, m1 in samples:
        sn, cn, dn = special.jacobiElliptic(u, m, m1)
        back = special.ellipticF(sn, m, m1)
        tolerance = 8 * EPS * (abs(u) + abs(sn) / (abs(cn) * dn))
        assert abs(back - u) <= tolerance, f"F(sn(u)) = {back!r}, u = {u!r}, m = {m!r}, m1 = {m1!r}"


@pytest.mark.parametrize("regime", ["generic", "m-near-0", "m-near-1", "m-extremely-near-1"])
def test_ellipticK_equals_F_at_1(regime):
    for m, m1 in parameter_samples(regime, rng_for("K=F" + regime), 20):
        quarter = special.ellipticK(m, m1) if m1 is not None else special.ellipticK(m)
        at_one = special.ellipticF(1.0, m, m1) if m1 is not None else special.ellipticF(1.0, m)
        assert abs(at_one / quarter - 1) <= 4 * EPS, (m, m1)


# ============================================================================================
# Complete integral K

K_BUDGETS = {
    "generic": 2e-15,
    "m-near-0": 2e-15,
    "m-near-1": 2e-15,
    "m-extremely-near-1": 2e-15,
}


@pytest.mark.parametrize("regime", sorted(K_BUDGETS))
def test_ellipticK(regime):
    errors = []
    for m, m1 in parameter_samples(regime, rng_for("K" + regime), 40):
        got = special.ellipticK(m, m1) if m1 is not None else special.ellipticK(m)
        with precision_for(m1):
            want = mpmath.ellipk(mp_parameter(m, m1))
            errors.append((float(abs((mpmath.mpf(got) - want) / want)), (m, m1)))
    error, where = worst(errors)
    assert error <= K_BUDGETS[regime], f"relative error {error:.3g} at (m, m1) = {where!r}"


def test_ellipticK_special_values():
    assert special.ellipticK(0.0) == pytest.approx(np.pi / 2, rel=EPS)
    assert special.ellipticK(1.0) == np.inf
    assert special.ellipticK(1.0, 0.0) == np.inf
    # m1 given explicitly is what counts near m = 1: K = ln 4 - ln(m1)/2 + O(m1 ln m1)
    assert special.ellipticK(1.0, 1e-300) == pytest.approx(np.log(4) + 150 * np.log(10),
                                                           rel=1e-15)


# ============================================================================================
# Incomplete integral F(x|m), x = sin(amplitude)

def F_errors(samples):
    errors = []
    for x, m, m1 in samples:
        got = special.ellipticF(x, m, m1) if m1 is not None else special.ellipticF(x, m)
        with precision_for(m1):
            want = mpmath.ellipf(mpmath.asin(mpmath.mpf(x)), mp_parameter(m, m1))
            error = float(abs((mpmath.mpf(got) - want) / want)) if want else abs(got)
            errors.append((error, (x, m, m1)))
    return errors


def F_samples(regime, count=40, x_kind="uniform"):
    rng = rng_for("F" + regime + x_kind)
    samples = []
    for m, m1 in parameter_samples(regime, rng, count):
        if x_kind == "uniform":
            x = rng.uniform(-1.0, 1.0)
        elif x_kind == "near-1":
            x = rng.choice([-1.0, 1.0]) * (1.0 - log_uniform(rng, 1e-16, 1e-1, 1)[0])
        else:  # small
            x = rng.choice([-1.0, 1.0]) * log_uniform(rng, 1e-300, 1e-2, 1)[0]
        samples.append((x, m, m1))
    return samples


F_BUDGETS = {
    ("generic", "uniform"): 2e-15,
    ("m-near-0", "uniform"): 2e-15,
    ("m-near-1", "uniform"): 2e-15,
    ("generic", "near-1"): 2e-15,
    ("m-near-0", "near-1"): 2e-15,
    ("m-near-1", "near-1"): 2e-15,
    ("generic", "small"): 1e-15,
}


@pytest.mark.parametrize("regime, x_kind", sorted(F_BUDGETS), ids=lambda x: str(x))
def test_ellipticF(regime, x_kind):
    samples = F_samples(regime, x_kind=x_kind)
    if x_kind == "near-1":
        samples += [(s * 1.0, m, m1) for s in (-1.0, 1.0)
                    for m, m1 in parameter_samples(regime, rng_for("F=K" + regime), 5)]
    error, where = worst(F_errors(samples))
    assert error <= F_BUDGETS[(regime, x_kind)], f"relative error {error:.3g} at (x, m, m1) = {where!r}"


@pytest.mark.parametrize("x", [0.0, 1e-10, 0.3, -0.7, 0.999, -1.0, 1.0])
def test_ellipticF_special_cases(x):
    assert special.ellipticF(x, 0.0) == pytest.approx(np.arcsin(x), rel=4 * EPS, abs=0)
    if abs(x) < 1:
        assert special.ellipticF(x, 1.0) == pytest.approx(np.arctanh(x), rel=4 * EPS, abs=0)
        assert special.ellipticF(x, 1.0, 0.0) == pytest.approx(np.arctanh(x), rel=4 * EPS,
                                                               abs=0)
    assert special.ellipticF(0.0, 0.37) == 0.0


# ============================================================================================
# Third kind Pi(n; x|m)

def Pi_errors(samples):
    errors = []
    for n, x, m, m1 in samples:
        got = special.ellipticPi(n, x, m, m1) if m1 is not None else special.ellipticPi(n, x, m)
        with precision_for(m1):
            want = mpmath.ellippi(mpmath.mpf(n), mpmath.asin(mpmath.mpf(x)), mp_parameter(m, m1))
            error = float(abs((mpmath.mpf(got) - want) / want)) if want else abs(got)
            errors.append((error, (n, x, m, m1)))
    return errors


def Pi_samples(regime, n_kind, count=30):
    rng = rng_for("Pi" + regime + n_kind)
    samples = []
    for m, m1 in parameter_samples(regime, rng, count):
        x = rng.uniform(-1.0, 1.0)
        if n_kind == "moderate":
            n = rng.uniform(-3.0, 0.9)
        elif n_kind == "large-negative":
            n = -log_uniform(rng, 3.0, 1e6, 1)[0]
        elif n_kind == "near-1":
            n = 1.0 - log_uniform(rng, 1e-8, 1e-2, 1)[0]
        elif n_kind == "above-1":  # n x^2 < 1 still
            n = log_uniform(rng, 1.01, 100.0, 1)[0]
            x = rng.uniform(-0.99, 0.99) / np.sqrt(n)
        elif n_kind == "x-near-1":
            n = rng.uniform(-3.0, 0.9)
            x = rng.choice([-1.0, 1.0]) * (1.0 - log_uniform(rng, 1e-16, 1e-1, 1)[0])
        samples.append((n, x, m, m1))
    return samples


PI_BUDGETS = {
    ("generic", "moderate"): 4e-15,
    ("m-near-0", "moderate"): 4e-15,
    ("m-near-1", "moderate"): 4e-15,
    # n = -3 ... -1e6: a well-conditioned regime (d ln Pi / d ln n -> -1/2)
    ("generic", "large-negative"): 1e-14,
    # n = 1 - 1e-8 ... 1 - 1e-2: forming 1 - n x^2 in double costs eps / (1 - n x^2)
    ("generic", "near-1"): 1e-13,
    ("generic", "above-1"): 4e-15,
    ("generic", "x-near-1"): 4e-15,
    ("m-near-1", "x-near-1"): 4e-15,
}


@pytest.mark.parametrize("regime, n_kind", sorted(PI_BUDGETS), ids=lambda x: str(x))
def test_ellipticPi(regime, n_kind):
    error, where = worst(Pi_errors(Pi_samples(regime, n_kind)))
    assert error <= PI_BUDGETS[(regime, n_kind)], \
        f"relative error {error:.3g} at (n, x, m, m1) = {where!r}"


@pytest.mark.parametrize("x", [0.0, 0.3, -0.7, 0.999, 1.0])
@pytest.mark.parametrize("m", [0.0, 0.4, 1.0 - 1e-9])
def test_ellipticPi_at_n_0_is_F(x, m):
    assert special.ellipticPi(0.0, x, m) == pytest.approx(special.ellipticF(x, m), rel=4 * EPS,
                                                          abs=0)


# ============================================================================================
# Carlson's R_F and R_J

def carlson_errors(function, mp_function, samples):
    errors = []
    for arguments in samples:
        got = function(*arguments)
        want = mp_function(*(mpmath.mpf(a) for a in arguments))
        errors.append((float(abs((mpmath.mpf(got) - want) / want)), arguments))
    return errors


def carlson_samples(kind, count, arity):
    rng = rng_for("carlson" + kind + str(arity))
    samples = []
    for _ in range(count):
        if kind == "generic":
            values = log_uniform(rng, 1e-3, 10.0, arity)
        elif kind == "one-zero":
            values = log_uniform(rng, 1e-3, 10.0, arity)
            values[rng.integers(0, 3)] = 0.0
        elif kind == "nearly-equal":
            values = rng.uniform(2.0, 3.0) * (1 + rng.uniform(-1e-8, 1e-8, arity))
        elif kind == "wide-scale":  # homogeneous: R_F of degree -1/2, R_J of -3/2
            values = log_uniform(rng, 0.1, 10.0, arity) * 10.0 ** rng.uniform(-60, 60)
        elif kind == "wide-spread":  # arguments many orders of magnitude apart
            values = log_uniform(rng, 1e-8, 1e8, arity)
        samples.append(tuple(float(v) for v in values))
    return samples


CARLSON_BUDGETS = {"generic": 4e-15, "one-zero": 4e-15, "nearly-equal": 4e-15,
                   "wide-scale": 4e-15, "wide-spread": 1e-14}


@pytest.mark.parametrize("kind", sorted(CARLSON_BUDGETS))
def test_carlsonRF(kind):
    samples = carlson_samples(kind, 40, 3)
    error, where = worst(carlson_errors(special.carlsonRF, mpmath.elliprf, samples))
    assert error <= CARLSON_BUDGETS[kind], f"relative error {error:.3g} at {where!r}"


@pytest.mark.parametrize("kind", sorted(CARLSON_BUDGETS))
def test_carlsonRJ(kind):
    samples = carlson_samples(kind, 40, 4)
    if kind == "one-zero":  # p must stay positive
        samples = [s[:3] + (s[3] or 0.5,) for s in samples]
    error, where = worst(carlson_errors(special.carlsonRJ, mpmath.elliprj, samples))
    assert error <= CARLSON_BUDGETS[kind], f"relative error {error:.3g} at {where!r}"


def test_carlson_special_values():
    for x in (1e-30, 0.25, 3.0, 1e30):
        assert special.carlsonRF(x, x, x) == pytest.approx(x**-0.5, rel=4 * EPS)
        assert special.carlsonRJ(x, x, x, x) == pytest.approx(x**-1.5, rel=4 * EPS)
    assert special.carlsonRF(0.0, 1.0, 1.0) == pytest.approx(np.pi / 2, rel=4 * EPS)
    # K(m) = R_F(0, 1 - m, 1)
    assert special.carlsonRF(0.0, 0.6, 1.0) == pytest.approx(special.ellipticK(0.4), rel=4 * EPS)


# ============================================================================================
# Bad input

BAD_SPECIAL_INPUT = [
    ("jacobiElliptic", (np.nan, 0.5)),
    ("jacobiElliptic", (np.inf, 0.5)),
    ("jacobiElliptic", (0.5, np.nan)),
    ("jacobiElliptic", (0.5, 1.5)),
    ("jacobiElliptic", (0.5, -0.5)),
    ("jacobiElliptic", (0.5, 0.5, -0.1)),
    ("ellipticK", (1.5,)),
    ("ellipticK", (-0.5,)),
    ("ellipticK", (np.nan,)),
    ("ellipticF", (1.5, 0.5)),
    ("ellipticF", (-1.0 - 1e-15, 0.5)),
    ("ellipticF", (np.nan, 0.5)),
    ("ellipticF", (0.5, 2.0)),
    ("ellipticPi", (2.0, 0.9, 0.5)),
    ("ellipticPi", (0.5, 1.5, 0.5)),
    ("ellipticPi", (0.5, 0.5, 1.5)),
    ("ellipticPi", (np.nan, 0.5, 0.5)),
    ("carlsonRF", (-1.0, 1.0, 1.0)),
    ("carlsonRF", (0.0, 0.0, 1.0)),
    ("carlsonRF", (np.nan, 1.0, 1.0)),
    ("carlsonRJ", (1.0, 1.0, 1.0, 0.0)),
    ("carlsonRJ", (1.0, 1.0, 1.0, -1.0)),
    ("carlsonRJ", (-1.0, 1.0, 1.0, 1.0)),
    ("carlsonRJ", (0.0, 0.0, 1.0, 1.0)),
    ("carlsonRJ", (1.0, 1.0, 1.0, np.nan)),
]


@pytest.mark.parametrize("name, arguments", BAD_SPECIAL_INPUT,
                         ids=[f"{name}{arguments}" for name, arguments in BAD_SPECIAL_INPUT])
def test_bad_special_input(name, arguments):
    with pytest.raises(openmm.OpenMMException, match=name):
        getattr(special, name)(*arguments)
