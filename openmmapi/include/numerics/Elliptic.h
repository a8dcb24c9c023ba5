#ifndef OPENMMRIGID_NUMERICS_ELLIPTIC_H_
#define OPENMMRIGID_NUMERICS_ELLIPTIC_H_

/*
 * Jacobi elliptic functions and Legendre elliptic integrals on plain doubles: the public, checked
 * entry points. Each checks its arguments, throws std::invalid_argument naming the problem, and
 * computes with the numerics core (numerics/core/CoreElliptic.h), which holds the algorithms and
 * their citations; ellipticF and ellipticPi, which no kernel needs, are written here on top of it.
 *
 * Convention: everything takes the PARAMETER m (not the modulus k = sqrt(m)) and, as a separate
 * argument, its complement m1 = 1 - m. Near m = 1 the caller usually knows m1 to full relative
 * precision (it is a ratio of conserved quantities), while 1 - m computed from a rounded m has lost
 * it; every function below uses m1 wherever 1 - m appears. The domain is 0 <= m <= 1.
 *
 * Accuracy (double precision, checked against mpmath in tests/python/test_special_functions.py):
 * - carlsonRF, carlsonRJ: a few ulps; the duplication is run until the Taylor remainder is below
 *   machine precision (Carlson, Numer. Algorithms 10 (1995) 13).
 * - ellipticK, ellipticF, ellipticPi: a few ulps relative. ellipticPi with n << -1 is computed as a
 *   difference of two terms and loses about log10(sqrt(|n|)) digits.
 * - jacobiElliptic: a few ulps relative to |f| + |u f'|, i.e. exact up to the rounding of u itself,
 *   also near m = 1 where cn and dn are exponentially small.
 */

#include "numerics/RigidCore.h"
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace OpenMMRigid {
namespace Special {

namespace detail {

inline void requireParameter(const char* function, double m, double m1) {
    if (!(m >= 0.0 && m <= 1.0 && m1 >= 0.0 && m1 <= 1.0))
        throw std::invalid_argument(std::string(function) + ": the parameter m = " + std::to_string(m) +
                " and its complement m1 = " + std::to_string(m1) + " must both lie in [0, 1]");
}

} // namespace detail

/**
 * Carlson's symmetric integral RF(x, y, z) = 1/2 int_0^inf dt / sqrt((t+x)(t+y)(t+z)) for
 * x, y, z >= 0 with at most one of them zero (DLMF 19.16.1), by the duplication theorem
 * (DLMF 19.26.18) and the seventh-order Taylor expansion of DLMF 19.36.1.
 *
 * @param x  the first argument, non-negative
 * @param y  the second argument, non-negative
 * @param z  the third argument, non-negative; at most one of x, y, z may be zero
 * @return RF(x, y, z)
 * @throws std::invalid_argument for arguments outside that domain
 */
inline double carlsonRF(double x, double y, double z) {
    if (!(x >= 0.0 && y >= 0.0 && z >= 0.0))
        throw std::invalid_argument("carlsonRF: arguments must be non-negative numbers");
    if ((x == 0.0) + (y == 0.0) + (z == 0.0) > 1)
        throw std::invalid_argument("carlsonRF: at most one argument may be zero (the integral diverges)");
    if (std::isinf(x) || std::isinf(y) || std::isinf(z))
        return 0.0;
    return rigidCarlsonRF(x, y, z);
}

/**
 * Carlson's symmetric integral RJ(x, y, z, p) = 3/2 int_0^inf dt / ((t+p) sqrt((t+x)(t+y)(t+z))) for
 * x, y, z >= 0 (at most one zero) and p > 0 (DLMF 19.16.2), by the duplication theorem with the
 * RC correction terms of Carlson (1995), eqs. (2.36)-(2.39), and DLMF 19.36.2.
 *
 * The argument of each RC term is e = prod_k (sqrt(p) - sqrt(x_k)) / (sqrt(p) + sqrt(x_k)) (the
 * ratio delta 4^-3n / d_n^2 of Carlson's paper, factored); 1 + e is formed from the complements
 * a_k = 1 - |ratio_k| so that it keeps full precision when p is far from x, y, z and e nears -1.
 *
 * @param x  the first argument, non-negative
 * @param y  the second argument, non-negative
 * @param z  the third argument, non-negative; at most one of x, y, z may be zero
 * @param p  the fourth argument, positive
 * @return RJ(x, y, z, p)
 * @throws std::invalid_argument for arguments outside that domain
 */
inline double carlsonRJ(double x, double y, double z, double p) {
    if (!(x >= 0.0 && y >= 0.0 && z >= 0.0 && p > 0.0))
        throw std::invalid_argument("carlsonRJ: x, y, z must be non-negative and p positive");
    if ((x == 0.0) + (y == 0.0) + (z == 0.0) > 1)
        throw std::invalid_argument("carlsonRJ: at most one of x, y, z may be zero (the integral diverges)");
    return rigidCarlsonRJ(x, y, z, p);
}

/**
 * The complete elliptic integral of the first kind K(m) = pi / (2 AGM(1, sqrt(m1))) (DLMF 19.8.5).
 *
 * @param m   the parameter, 0 <= m <= 1
 * @param m1  its complement 1 - m, 0 <= m1 <= 1 (pass it when it is known more precisely than 1 - m)
 * @return K(m), infinite for m = 1
 * @throws std::invalid_argument for m or m1 outside [0, 1]
 */
inline double ellipticK(double m, double m1) {
    detail::requireParameter("ellipticK", m, m1);
    return rigidEllipticK(m1);
}

/**
 * The incomplete elliptic integral of the first kind written with the Jacobi functions of its
 * value: for u in [-K, K], returns u given sn(u), cn(u)^2 and dn(u)^2 (DLMF 19.25.5 with
 * sin(phi) = sn, cos(phi)^2 = cn^2, 1 - m sin(phi)^2 = dn^2). Passing cn^2 and dn^2 rather than
 * deriving them from sn keeps full precision near the turning points sn = +-1.
 */
inline double ellipticFFromJacobi(double sn, double cn2, double dn2) {
    return sn*carlsonRF(cn2, dn2, 1.0);
}

/**
 * The incomplete elliptic integral of the first kind F(x|m) = int_0^x dt / sqrt((1-t^2)(1-m t^2)) for
 * -1 <= x <= 1, i.e. F(phi|m) with x = sin(phi) (DLMF 19.2.4; van Zon & Schofield (2007) eq. (3.42)).
 * Then F(sn(u|m)|m) = u for |u| <= K(m).
 *
 * @param x   the upper limit, -1 <= x <= 1
 * @param m   the parameter, 0 <= m <= 1
 * @param m1  its complement 1 - m, 0 <= m1 <= 1 (pass it when it is known more precisely than 1 - m)
 * @return F(x|m)
 * @throws std::invalid_argument for arguments outside that domain
 */
inline double ellipticF(double x, double m, double m1) {
    detail::requireParameter("ellipticF", m, m1);
    if (!(std::fabs(x) <= 1.0))
        throw std::invalid_argument("ellipticF: the argument x = sin(amplitude) must lie in [-1, 1]");
    double cos2 = (1.0 - x)*(1.0 + x);
    if (cos2 == 0.0 && m1 == 0.0)
        return std::copysign(std::numeric_limits<double>::infinity(), x);  // F(1|1) = atanh(1)
    return ellipticFFromJacobi(x, cos2, m1 + m*cos2);
}

/**
 * The incomplete elliptic integral of the third kind in the Jacobi functions of its upper limit:
 * for u in [-K, K], int_0^u du' / (1 - n sn(u')^2) = Pi(n; am(u) | m) (DLMF 19.25.14).
 */
inline double ellipticPiFromJacobi(double n, double sn, double cn2, double dn2) {
    double sn2 = sn*sn;
    return sn*carlsonRF(cn2, dn2, 1.0) + n/3.0*sn*sn2*carlsonRJ(cn2, dn2, 1.0, 1.0 - n*sn2);
}

/**
 * The incomplete elliptic integral of the third kind
 * Pi(n; x|m) = int_0^x dt / ((1 - n t^2) sqrt((1-t^2)(1-m t^2))) for -1 <= x <= 1 and n x^2 < 1
 * (DLMF 19.2.7 with x = sin(phi); DLMF's alpha^2 is n).
 *
 * @param n   the characteristic, with n x^2 < 1
 * @param x   the upper limit, -1 <= x <= 1
 * @param m   the parameter, 0 <= m <= 1
 * @param m1  its complement 1 - m, 0 <= m1 <= 1 (pass it when it is known more precisely than 1 - m)
 * @return Pi(n; x|m)
 * @throws std::invalid_argument for arguments outside that domain
 */
inline double ellipticPi(double n, double x, double m, double m1) {
    detail::requireParameter("ellipticPi", m, m1);
    if (!(std::fabs(x) <= 1.0))
        throw std::invalid_argument("ellipticPi: the argument x = sin(amplitude) must lie in [-1, 1]");
    if (!(n*x*x < 1.0))
        throw std::invalid_argument("ellipticPi: the characteristic n must satisfy n x^2 < 1");
    double cos2 = (1.0 - x)*(1.0 + x);
    if (cos2 == 0.0 && m1 == 0.0)
        return std::copysign(std::numeric_limits<double>::infinity(), x);
    double delta2 = m1 + m*cos2;
    if (n >= -1.0 || x == 0.0)
        return ellipticPiFromJacobi(n, x, cos2, delta2);
    // For n < -1 the two terms of DLMF 19.25.14 cancel (Pi is O(1/sqrt(-n)) while each term is O(F)).
    // The relation between the characteristics n and m/n (DLMF §19.7(iii)), with c = 1/x^2, gives
    // Pi(n) in terms of Pi(m/n), |m/n| < 1 (checked against mpmath in the tests):
    //   Pi(n) = F - Pi(m/n) + sqrt(c) RC((c - 1)(c - m), (c - n)(c - m/n)),
    // where F - Pi(m/n) = -(m/n)/3 x^3 RJ(cos^2, Delta^2, 1, 1 - (m/n) x^2) (DLMF 19.25.14) and, by the
    // homogeneity of RC, sqrt(c) RC(...) = x RC(a, b) with a = cos^2 Delta^2, b = (1 - n x^2)(1 - (m/n) x^2),
    // b - a = x^2 (1 + m - n - m/n) > 0, so RC(a, b) = atan(sqrt((b - a)/a)) / sqrt(b - a) (DLMF 19.2.18).
    // Every term is positive: no cancellation.
    const double x2 = x*x, ratio = m/n;
    double excess = -ratio/3.0*x*x2*carlsonRJ(cos2, delta2, 1.0, 1.0 - ratio*x2);
    double a = cos2*delta2, gap = x2*(1.0 + m - n - ratio);
    double rc = (a == 0.0 ? M_PI/2.0 : std::atan(std::sqrt(gap/a)))/std::sqrt(gap);
    return excess + x*rc;
}

/**
 * The Jacobi elliptic functions sn, cn, dn of (u|m) by the descending Gauss transformation
 * (DLMF 22.7.1-22.7.3): with k = sqrt(m), k' = sqrt(m1) and k_{n+1} = (1 - k_n')/(1 + k_n'), the
 * functions of (z_n, k_n) follow from those of (z_{n+1} = z_n/(1 + k_{n+1}), k_{n+1}) by
 *   sn_n = (1 + k_{n+1}) sn_{n+1} / (1 + k_{n+1} sn_{n+1}^2),  cn_n = cn_{n+1} dn_{n+1} / (1 + k_{n+1} sn_{n+1}^2),
 * and dn_n = sqrt(k_n'^2 + k_n^2 cn_n^2) (no cancellation). The moduli fall quadratically to zero, where
 * sn = sin and cn = cos (DLMF 22.5(ii)); the last argument is rescaled by pi/(2 K(m_N)) so that the
 * period is right to machine precision however large u is. Every step is a product or quotient of
 * positive factors, so cn and dn keep their relative accuracy near m = 1, where they are
 * exponentially small over most of the period. m = 0 and m = 1 are the trigonometric and hyperbolic
 * limits (DLMF 22.5(ii)). Below m1 = 1e-32 the levels with k_n = 1 to machine precision would
 * double the rounding error of cn at each level, so jacobiEllipticNearOne() takes over there.
 *
 * @param u   the argument, finite
 * @param m   the parameter, 0 <= m <= 1
 * @param m1  its complement 1 - m, 0 <= m1 <= 1 (pass it when it is known more precisely than 1 - m)
 * @param[out] sn  sn(u|m)
 * @param[out] cn  cn(u|m)
 * @param[out] dn  dn(u|m)
 * @throws std::invalid_argument for a non-finite u, or m or m1 outside [0, 1]
 */
inline void jacobiElliptic(double u, double m, double m1, double& sn, double& cn, double& dn) {
    detail::requireParameter("jacobiElliptic", m, m1);
    if (!std::isfinite(u))
        throw std::invalid_argument("jacobiElliptic: the argument u must be finite");
    RigidJacobi f;
    rigidJacobiElliptic(u, m, m1, &f);
    sn = f.sn;
    cn = f.cn;
    dn = f.dn;
}

} // namespace Special
} // namespace OpenMMRigid

#endif // OPENMMRIGID_NUMERICS_ELLIPTIC_H_
