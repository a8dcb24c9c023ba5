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
 * - jacobiElliptic: a few ulps relative to |f| + |u f'|, i.e. exact up to the rounding of u itself,
 *   also near m = 1 where cn and dn are exponentially small.
 */

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace OpenMMRigid {
namespace Special {

namespace detail {

// Duplication in Carlson's algorithms stops once 4^-n Q < |A_n|, with Q = (3 eps)^(-1/8) max|A_0 - x|
// for RF (whose series below keeps the seventh-order terms of DLMF 19.36.1, one duplication fewer
// than the fifth-order series needs) and (eps/4)^(-1/6) max|A_0 - x| for RJ: the Taylor remainder
// is then below machine precision (Carlson, Numer. Algorithms 10 (1995) 13, eqs. (2.2) and (2.36)).
inline const double rfStopFactor = std::pow(3.0*std::numeric_limits<double>::epsilon(), -1.0/8.0);
inline const double rjStopFactor = std::pow(0.25*std::numeric_limits<double>::epsilon(), -1.0/6.0);

inline void requireParameter(const char* function, double m, double m1) {
    if (!(m >= 0.0 && m <= 1.0 && m1 >= 0.0 && m1 <= 1.0))
        throw std::invalid_argument(std::string(function) + ": the parameter m = " + std::to_string(m) +
                " and its complement m1 = " + std::to_string(m1) + " must both lie in [0, 1]");
}

/**
 * RF(x[k], y[k], z[k]) for N argument triples at once (see carlsonRF below). The duplications of
 * the N integrals run in lockstep until every one has reached its stopping point, so that their
 * square roots overlap in the processor; a duplication beyond an integral's own stopping point only
 * makes its Taylor remainder smaller. The arguments must be finite and non-negative, with at most one
 * zero per triple (carlsonRF checks this; FreeRotor guarantees it). x, y and z are overwritten.
 */
template <int N>
inline void carlsonRFLockstep(double (&x)[N], double (&y)[N], double (&z)[N], double (&result)[N]) {
    double mean[N], mean0[N], x0[N], y0[N], q[N];
    for (int k = 0; k < N; k++) {
        mean[k] = mean0[k] = (x[k] + y[k] + z[k])/3.0;
        x0[k] = x[k];
        y0[k] = y[k];
        q[k] = rfStopFactor*std::max({std::fabs(mean[k] - x[k]), std::fabs(mean[k] - y[k]), std::fabs(mean[k] - z[k])});
    }
    double scale = 1.0;  // 4^-n
    auto converged = [&]() {
        for (int k = 0; k < N; k++)
            if (q[k]*scale >= std::fabs(mean[k]))
                return false;
        return true;
    };
    while (!converged()) {
        // DLMF 19.26.18: RF(x, y, z) = RF((x + l)/4, (y + l)/4, (z + l)/4), l = sqrt(xy) + sqrt(yz) + sqrt(zx).
        for (int k = 0; k < N; k++) {
            double sx = std::sqrt(x[k]), sy = std::sqrt(y[k]), sz = std::sqrt(z[k]);
            double lambda = sx*sy + sy*sz + sz*sx;
            x[k] = 0.25*(x[k] + lambda);
            y[k] = 0.25*(y[k] + lambda);
            z[k] = 0.25*(z[k] + lambda);
            mean[k] = 0.25*(mean[k] + lambda);
        }
        scale *= 0.25;
    }
    for (int k = 0; k < N; k++) {
        // DLMF 19.36.1 in the elementary symmetric functions e2, e3 of the scaled deviations.
        double dx = (mean0[k] - x0[k])*scale/mean[k];
        double dy = (mean0[k] - y0[k])*scale/mean[k];
        double dz = -dx - dy;
        double e2 = dx*dy - dz*dz;
        double e3 = dx*dy*dz;
        result[k] = (1.0 - e2/10.0 + e3/14.0 + e2*e2/24.0 - 3.0*e2*e3/44.0 - 5.0*e2*e2*e2/208.0 + 3.0*e3*e3/104.0 +
                     e2*e2*e3/16.0)/std::sqrt(mean[k]);
    }
}

} // namespace detail

/**
 * Carlson's symmetric integral RF(x, y, z) = 1/2 int_0^inf dt / sqrt((t+x)(t+y)(t+z)) for
 * x, y, z >= 0 with at most one of them zero (DLMF 19.16.1), by the duplication theorem
 * (DLMF 19.26.18) and the seventh-order Taylor expansion of DLMF 19.36.1.
 */
inline double carlsonRF(double x, double y, double z) {
    if (!(x >= 0.0 && y >= 0.0 && z >= 0.0))
        throw std::invalid_argument("carlsonRF: arguments must be non-negative numbers");
    if ((x == 0.0) + (y == 0.0) + (z == 0.0) > 1)
        throw std::invalid_argument("carlsonRF: at most one argument may be zero (the integral diverges)");
    if (std::isinf(x) || std::isinf(y) || std::isinf(z))
        return 0.0;
    double result[1], xs[1] = {x}, ys[1] = {y}, zs[1] = {z};
    detail::carlsonRFLockstep<1>(xs, ys, zs, result);
    return result[0];
}

/**
 * Carlson's degenerate integral RC(1, 1 + e) for e > -1 (DLMF 19.2.17 and 19.2.18): atan(sqrt(e))/sqrt(e)
 * for e > 0 and atanh(sqrt(-e))/sqrt(-e) for e < 0, with a series near e = 0. The caller passes 1 + e
 * as well, computed without cancellation, since near e = -1 the result depends on it alone.
 */
inline double carlsonRCOnePlus(double e, double onePlusE) {
    if (std::fabs(e) < 1e-4)
        return 1.0 - e*(1.0/3.0 - e*(1.0/5.0 - e*(1.0/7.0 - e/9.0)));
    double s = std::sqrt(std::fabs(e));
    if (e > 0.0)
        return std::atan(s)/s;
    if (e > -0.5)
        return std::atanh(s)/s;
    // atanh(s) = ln((1 + s)/(1 - s))/2 and 1 - s = (1 + e)/(1 + s), exact near e = -1.
    return std::log((1.0 + s)*(1.0 + s)/onePlusE)/(2.0*s);
}

/**
 * Carlson's symmetric integral RJ(x, y, z, p) = 3/2 int_0^inf dt / ((t+p) sqrt((t+x)(t+y)(t+z))) for
 * x, y, z >= 0 (at most one zero) and p > 0 (DLMF 19.16.2), by the duplication theorem with the
 * RC correction terms of Carlson (1995), eqs. (2.36)-(2.39), and DLMF 19.36.2.
 *
 * The argument of each RC term is e = prod_k (sqrt(p) - sqrt(x_k)) / (sqrt(p) + sqrt(x_k)) (the
 * ratio delta 4^-3n / d_n^2 of Carlson's paper, factored); 1 + e is formed from the complements
 * a_k = 1 - |ratio_k| so that it keeps full precision when p is far from x, y, z and e nears -1.
 */
inline double carlsonRJ(double x, double y, double z, double p) {
    if (!(x >= 0.0 && y >= 0.0 && z >= 0.0 && p > 0.0))
        throw std::invalid_argument("carlsonRJ: x, y, z must be non-negative and p positive");
    if ((x == 0.0) + (y == 0.0) + (z == 0.0) > 1)
        throw std::invalid_argument("carlsonRJ: at most one of x, y, z may be zero (the integral diverges)");
    double mean = (x + y + z + 2.0*p)/5.0;
    const double mean0 = mean;
    const double x0 = x, y0 = y, z0 = z;
    double q = detail::rjStopFactor*
               std::max({std::fabs(mean - x), std::fabs(mean - y), std::fabs(mean - z), std::fabs(mean - p)});
    double scale = 1.0;  // 4^-n
    double sum = 0.0;
    while (q*scale >= std::fabs(mean)) {
        double sx = std::sqrt(x), sy = std::sqrt(y), sz = std::sqrt(z), sp = std::sqrt(p);
        double lambda = sx*sy + sy*sz + sz*sx;
        double d = (sp + sx)*(sp + sy)*(sp + sz);
        double e = 1.0, complement[3], sign = 1.0;
        const double roots[3] = {sx, sy, sz};
        for (int k = 0; k < 3; k++) {
            double ratio = (sp - roots[k])/(sp + roots[k]);
            complement[k] = 2.0*std::min(sp, roots[k])/(sp + roots[k]);  // 1 - |ratio|
            e *= ratio;
            if (ratio < 0.0)
                sign = -sign;
        }
        // 1 + e; for sign -1 it is 1 - prod(1 - a_k) = a3 + (1 - a3)(a2 + (1 - a2) a1), a sum of positive terms.
        double onePlusE = (sign > 0.0 ? 1.0 + e :
                complement[2] + (1.0 - complement[2])*(complement[1] + (1.0 - complement[1])*complement[0]));
        sum += scale/d*carlsonRCOnePlus(e, onePlusE);
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

namespace detail {

/**
 * sn, cn, dn for m1 < 1e-32, where K = ln(4/sqrt(m1)) + O(m1) is at least 37. The argument is reduced
 * by the periods and symmetries (DLMF 22.4(ii)) to w in [0, K]; for w <= K/2 the expansion about
 * m = 1 of DLMF 22.10.2 (first order in m1; the next order is below (m1 e^{2w})^2 < 16 m1 relative)
 * gives the functions, and for w > K/2 the shift by K (DLMF 22.4.3),
 * sn(K - v) = cn(v)/dn(v), cn(K - v) = k' sn(v)/dn(v), dn(K - v) = k'/dn(v), brings the argument back
 * to v = K - w < K/2. Each result is a product of relatively accurate factors.
 */
inline void jacobiEllipticNearOne(double u, double m, double m1, double& sn, double& cn, double& dn) {
    (void) m;
    const double quarter = std::log(4.0/std::sqrt(m1));  // K(m) up to O(m1 K) (DLMF 19.12.1)
    double w = std::remainder(u, 4.0*quarter);            // sn, cn have period 4K
    double snSign = (w < 0.0 ? -1.0 : 1.0), cnSign = 1.0;
    w = std::fabs(w);
    if (w > quarter) {  // sn(2K - w) = sn(w), cn(2K - w) = -cn(w), dn(2K - w) = dn(w)
        w = 2.0*quarter - w;
        cnSign = -1.0;
    }
    auto expansion = [m1](double x, double& s, double& c, double& d) {
        double t = std::tanh(x), h = 1.0/std::cosh(x);
        double sinhCosh = std::sinh(x)*std::cosh(x);
        s = t + 0.25*m1*(sinhCosh - x)*h*h;
        c = h - 0.25*m1*(sinhCosh - x)*t*h;
        d = h + 0.25*m1*(sinhCosh + x)*t*h;
    };
    double s, c, d;
    if (w <= 0.5*quarter)
        expansion(w, s, c, d);
    else {
        double vs, vc, vd, kc = std::sqrt(m1);
        expansion(quarter - w, vs, vc, vd);
        s = vc/vd;
        c = kc*vs/vd;
        d = kc/vd;
    }
    sn = snSign*s;
    cn = cnSign*c;
    dn = d;
}

} // namespace detail

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
    if (m1 < 1e-32)
        return detail::jacobiEllipticNearOne(u, m, m1, sn, cn, dn);
    const int maxLevels = 40;
    double modulus[maxLevels + 1], complement[maxLevels + 1];
    modulus[0] = std::sqrt(m);
    complement[0] = std::sqrt(m1);
    double z = u;
    int levels = 0;
    while (modulus[levels] > 1e-9 && levels < maxLevels) {
        double kc = complement[levels];
        modulus[levels + 1] = (1.0 - kc)/(1.0 + kc);
        complement[levels + 1] = 2.0*std::sqrt(kc)/(1.0 + kc);
        z /= 1.0 + modulus[levels + 1];
        levels++;
    }
    // K(m_N) = (pi/2)(1 + m_N/4 + O(m_N^2)) (DLMF 19.5.1).
    z /= 1.0 + 0.25*modulus[levels]*modulus[levels];
    double s = std::sin(z), c = std::cos(z);
    double d = std::sqrt(1.0 - modulus[levels]*modulus[levels]*s*s);
    for (int n = levels; n > 0; n--) {
        double k = modulus[n];
        double denominator = 1.0 + k*s*s;
        double nextS = (1.0 + k)*s/denominator;
        c = c*d/denominator;
        s = nextS;
        d = std::sqrt(complement[n - 1]*complement[n - 1] + modulus[n - 1]*modulus[n - 1]*c*c);
    }
    // Put (sn, cn) back on the unit circle; a common factor keeps the relative accuracy of each.
    double radius = std::sqrt(s*s + c*c);
    sn = s/radius;
    cn = c/radius;
    dn = std::sqrt(m1 + m*cn*cn);
}

} // namespace Special
} // namespace OpenMMRigid

#endif // OPENMMRIGID_NUMERICS_ELLIPTIC_H_
