#ifndef OPENMMRIGID_NUMERICS_ELLIPTIC_H_
#define OPENMMRIGID_NUMERICS_ELLIPTIC_H_

/*
 * Jacobi elliptic functions and Legendre elliptic integrals on plain doubles.
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
 * - jacobiElliptic: absolute error of a few ulps for |u| of order K; for large |u| the error grows
 *   like |u| times machine epsilon, which is inherent in the rounding of u itself.
 */

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace OpenMMRigid {
namespace Special {

namespace detail {

// Duplication in Carlson's algorithms stops once 4^-n Q < |A_n|, with Q = (3 eps)^(-1/6) max|A_0 - x|
// for RF and (eps/4)^(-1/6) max|A_0 - x| for RJ: the Taylor remainder is then below machine
// precision (Carlson, Numer. Algorithms 10 (1995) 13, eqs. (2.2) and (2.36)).
inline const double rfStopFactor = std::pow(3.0*std::numeric_limits<double>::epsilon(), -1.0/6.0);
inline const double rjStopFactor = std::pow(0.25*std::numeric_limits<double>::epsilon(), -1.0/6.0);

inline void requireParameter(const char* function, double m, double m1) {
    if (!(m >= 0.0 && m <= 1.0 && m1 >= 0.0 && m1 <= 1.0))
        throw std::invalid_argument(std::string(function) + ": the parameter m = " + std::to_string(m) +
                " and its complement m1 = " + std::to_string(m1) + " must both lie in [0, 1]");
}

} // namespace detail

/**
 * Carlson's symmetric integral RF(x, y, z) = 1/2 int_0^inf dt / sqrt((t+x)(t+y)(t+z)) for
 * x, y, z >= 0 with at most one of them zero (DLMF 19.16.1), by the duplication theorem
 * (DLMF 19.26.18) and the fifth-order Taylor expansion of DLMF 19.36.1.
 */
inline double carlsonRF(double x, double y, double z) {
    if (!(x >= 0.0 && y >= 0.0 && z >= 0.0))
        throw std::invalid_argument("carlsonRF: arguments must be non-negative numbers");
    if ((x == 0.0) + (y == 0.0) + (z == 0.0) > 1)
        return std::numeric_limits<double>::infinity();
    if (std::isinf(x) || std::isinf(y) || std::isinf(z))
        return 0.0;
    double mean = (x + y + z)/3.0;
    const double mean0 = mean;
    double q = detail::rfStopFactor*
               std::max({std::fabs(mean - x), std::fabs(mean - y), std::fabs(mean - z)});
    double scale = 1.0;  // 4^-n
    const double x0 = x, y0 = y;
    while (q*scale >= std::fabs(mean)) {
        double sx = std::sqrt(x), sy = std::sqrt(y), sz = std::sqrt(z);
        double lambda = sx*sy + sy*sz + sz*sx;
        x = 0.25*(x + lambda);
        y = 0.25*(y + lambda);
        z = 0.25*(z + lambda);
        mean = 0.25*(mean + lambda);
        scale *= 0.25;
    }
    double dx = (mean0 - x0)*scale/mean;
    double dy = (mean0 - y0)*scale/mean;
    double dz = -dx - dy;
    double e2 = dx*dy - dz*dz;
    double e3 = dx*dy*dz;
    return (1.0 - e2/10.0 + e3/14.0 + e2*e2/24.0 - 3.0*e2*e3/44.0)/std::sqrt(mean);
}

/**
 * Carlson's degenerate integral RC(1, 1 + e) for e > -1 (DLMF 19.2.17 and 19.2.18): atan(sqrt(e))/sqrt(e)
 * for e > 0 and atanh(sqrt(-e))/sqrt(-e) for e < 0, with a series near e = 0.
 */
inline double carlsonRCOnePlus(double e) {
    if (std::fabs(e) < 1e-4)
        return 1.0 - e*(1.0/3.0 - e*(1.0/5.0 - e*(1.0/7.0 - e/9.0)));
    if (e > 0.0) {
        double s = std::sqrt(e);
        return std::atan(s)/s;
    }
    double s = std::sqrt(-e);
    return std::atanh(s)/s;
}

/**
 * Carlson's symmetric integral RJ(x, y, z, p) = 3/2 int_0^inf dt / ((t+p) sqrt((t+x)(t+y)(t+z))) for
 * x, y, z >= 0 (at most one zero) and p > 0 (DLMF 19.16.2), by the duplication theorem with the
 * RC correction terms of Carlson (1995), eqs. (2.36)-(2.39), and DLMF 19.36.2.
 */
inline double carlsonRJ(double x, double y, double z, double p) {
    if (!(x >= 0.0 && y >= 0.0 && z >= 0.0 && p > 0.0))
        throw std::invalid_argument("carlsonRJ: x, y, z must be non-negative and p positive");
    if ((x == 0.0) + (y == 0.0) + (z == 0.0) > 1)
        return std::numeric_limits<double>::infinity();
    double mean = (x + y + z + 2.0*p)/5.0;
    const double mean0 = mean;
    const double x0 = x, y0 = y, z0 = z;
    const double delta = (p - x)*(p - y)*(p - z);
    double q = detail::rjStopFactor*
               std::max({std::fabs(mean - x), std::fabs(mean - y), std::fabs(mean - z), std::fabs(mean - p)});
    double scale = 1.0;  // 4^-n
    double sum = 0.0;
    while (q*scale >= std::fabs(mean)) {
        double sx = std::sqrt(x), sy = std::sqrt(y), sz = std::sqrt(z), sp = std::sqrt(p);
        double lambda = sx*sy + sy*sz + sz*sx;
        double d = (sp + sx)*(sp + sy)*(sp + sz);
        double e = delta*scale*scale*scale/(d*d);
        sum += scale/d*carlsonRCOnePlus(e);
        x = 0.25*(x + lambda);
        y = 0.25*(y + lambda);
        z = 0.25*(z + lambda);
        p = 0.25*(p + lambda);
        mean = 0.25*(mean + lambda);
        scale *= 0.25;
    }
    double dx = (mean0 - x0)*scale/mean;
    double dy = (mean0 - y0)*scale/mean;
    double dz = (mean0 - z0)*scale/mean;
    double dp = -0.5*(dx + dy + dz);
    double e2 = dx*dy + dx*dz + dy*dz - 3.0*dp*dp;
    double e3 = dx*dy*dz + 2.0*e2*dp + 4.0*dp*dp*dp;
    double e4 = (2.0*dx*dy*dz + e2*dp + 3.0*dp*dp*dp)*dp;
    double e5 = dx*dy*dz*dp*dp;
    double series = 1.0 - 3.0*e2/14.0 + e3/6.0 + 9.0*e2*e2/88.0 - 3.0*e4/22.0 - 9.0*e2*e3/52.0 + 3.0*e5/26.0;
    return scale*series/(mean*std::sqrt(mean)) + 6.0*sum;
}

/** The complete elliptic integral of the first kind K(m) = pi / (2 AGM(1, sqrt(m1))) (DLMF 19.8.5). */
inline double ellipticK(double m, double m1) {
    detail::requireParameter("ellipticK", m, m1);
    if (m1 == 0.0)
        return std::numeric_limits<double>::infinity();
    double a = 1.0, b = std::sqrt(m1);
    while (std::fabs(a - b) > 2.0*std::numeric_limits<double>::epsilon()*a) {
        double next = 0.5*(a + b);
        b = std::sqrt(a*b);
        a = next;
    }
    return M_PI/(a + b);
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
 */
inline double ellipticF(double x, double m, double m1) {
    detail::requireParameter("ellipticF", m, m1);
    if (!(std::fabs(x) <= 1.0))
        throw std::invalid_argument("ellipticF: the argument x = sin(amplitude) must lie in [-1, 1]");
    double cos2 = (1.0 - x)*(1.0 + x);
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
 */
inline double ellipticPi(double n, double x, double m, double m1) {
    detail::requireParameter("ellipticPi", m, m1);
    if (!(std::fabs(x) <= 1.0))
        throw std::invalid_argument("ellipticPi: the argument x = sin(amplitude) must lie in [-1, 1]");
    if (!(n*x*x < 1.0))
        throw std::invalid_argument("ellipticPi: the characteristic n must satisfy n x^2 < 1");
    double cos2 = (1.0 - x)*(1.0 + x);
    return ellipticPiFromJacobi(n, x, cos2, m1 + m*cos2);
}

/**
 * The Jacobi elliptic functions sn, cn, dn of (u|m) by the descending Landen transformation
 * (the arithmetic-geometric mean scale, DLMF 22.20(ii)); m = 0 and m = 1 are the trigonometric and
 * hyperbolic limits (DLMF 22.5(ii)). dn is taken as sqrt(m1 + m cn^2), which has no cancellation.
 */
inline void jacobiElliptic(double u, double m, double m1, double& sn, double& cn, double& dn) {
    detail::requireParameter("jacobiElliptic", m, m1);
    if (!std::isfinite(u))
        throw std::invalid_argument("jacobiElliptic: the argument u must be finite");
    if (m == 0.0) {
        sn = std::sin(u);
        cn = std::cos(u);
        dn = 1.0;
        return;
    }
    if (m1 == 0.0) {
        sn = std::tanh(u);
        cn = 1.0/std::cosh(u);
        dn = cn;
        return;
    }
    const int maxLevels = 32;  // the AGM converges quadratically; 32 levels reach m1 = 1e-300
    double a[maxLevels + 1], c[maxLevels + 1];
    a[0] = 1.0;
    double b = std::sqrt(m1);
    c[0] = std::sqrt(m);
    int levels = 0;
    while (std::fabs(c[levels]) > std::numeric_limits<double>::epsilon()*a[levels] && levels < maxLevels) {
        a[levels + 1] = 0.5*(a[levels] + b);
        c[levels + 1] = 0.5*(a[levels] - b);
        b = std::sqrt(a[levels]*b);
        levels++;
    }
    // phi_N = 2^N a_N u, then phi_{n-1} = (phi_n + asin(c_n sin(phi_n) / a_n)) / 2  (DLMF 22.20.5).
    double phi = std::ldexp(a[levels]*u, levels);
    for (int n = levels; n > 0; n--)
        phi = 0.5*(phi + std::asin(c[n]*std::sin(phi)/a[n]));
    sn = std::sin(phi);
    cn = std::cos(phi);
    dn = std::sqrt(m1 + m*cn*cn);
}

} // namespace Special
} // namespace OpenMMRigid

#endif // OPENMMRIGID_NUMERICS_ELLIPTIC_H_
