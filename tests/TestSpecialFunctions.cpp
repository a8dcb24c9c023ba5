/* -------------------------------------------------------------------------- *
 *                               OpenMM-Rigid                                 *
 * -------------------------------------------------------------------------- *
 * Tests of the Jacobi elliptic functions, Legendre elliptic integrals and    *
 * Carlson symmetric integrals in numerics/Elliptic.h.                        *
 *                                                                            *
 * Every check compares against something known: an identity that holds for  *
 * every argument (DLMF 22.6, 22.4, 19.7, 19.20, 19.25), a closed form at     *
 * m = 0 and m = 1 (DLMF 22.5(ii)), or a value computed with mpmath at 340    *
 * digits. Error budgets are grouped by regime and stated in units of the     *
 * machine epsilon; where an argument is large the budget grows like |u| eps, *
 * which is the rounding of the argument itself, and where the inverse of a   *
 * function is ill-conditioned the budget includes the condition number.      *
 * -------------------------------------------------------------------------- */

#include "numerics/Elliptic.h"
#include "openmm/internal/AssertionUtilities.h"
#include <cmath>
#include <iostream>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

using namespace OpenMM;
using namespace OpenMMRigid::Special;

static const double EPS = std::numeric_limits<double>::epsilon();

/** A parameter m together with its complement m1 = 1 - m, given independently as the API expects. */
struct Parameter {
    double m, m1;
};

/**
 * Parameters from m = 0 to m = 1. Near m = 1 the complement is passed explicitly down to 1e-300,
 * where m itself rounds to 1 and only m1 carries the information.
 */
static std::vector<Parameter> parameterGrid() {
    std::vector<Parameter> grid = {{0.0, 1.0}, {1e-300, 1.0}, {1e-10, 1.0 - 1e-10}, {0.1, 0.9}, {0.3, 0.7},
                                   {0.5, 0.5}, {0.7, 0.3}, {0.9, 1.0 - 0.9}, {0.99, 1.0 - 0.99}};
    for (double m1 : {1e-3, 1e-6, 1e-9, 1e-12, 1e-15, 1e-20, 1e-50, 1e-100, 1e-200, 1e-300})
        grid.push_back({1.0 - m1, m1});
    grid.push_back({1.0, 0.0});
    return grid;
}

static std::vector<double> argumentGrid() {
    return {0.0, 1e-8, 0.3, -0.3, 1.0, -1.0, 2.5, -2.5, 7.0, -7.0, 30.0, -30.0, 123.456, -400.0};
}

static std::string describe(double u, const Parameter& p) {
    std::stringstream s;
    s.precision(17);
    s << "u = " << u << ", m = " << p.m << ", m1 = " << p.m1;
    return s.str();
}

/** Fails with a message naming the inputs when |expected - found| > tol (an absolute tolerance). */
static void assertClose(double expected, double found, double tol, const std::string& where, int line) {
    if (!(std::fabs(expected - found) <= tol)) {
        std::stringstream details;
        details.precision(17);
        details << "Expected " << expected << ", found " << found << " (difference " << std::fabs(expected - found)
                << ", tolerance " << tol << ") at " << where;
        throwException(__FILE__, line, details.str());
    }
}

/** Relative comparison against a reference value. */
static void assertRelative(double expected, double found, double tol, const std::string& where, int line) {
    assertClose(expected, found, tol*std::fabs(expected), where, line);
}

template <class Function>
static void assertThrowsInvalidArgument(Function function, const std::string& what, int line) {
    try {
        function();
    }
    catch (const std::invalid_argument&) {
        return;
    }
    throwException(__FILE__, line, what + " did not throw std::invalid_argument");
}

/** sn^2 + cn^2 = 1 and dn^2 + m sn^2 = 1 (DLMF 22.6.1) for every parameter and argument. */
void testPythagoreanIdentities() {
    for (const Parameter& p : parameterGrid())
        for (double u : argumentGrid()) {
            double sn, cn, dn;
            jacobiElliptic(u, p.m, p.m1, sn, cn, dn);
            assertClose(1.0, sn*sn + cn*cn, 8*EPS, describe(u, p), __LINE__);
            assertClose(1.0, dn*dn + p.m*sn*sn, 8*EPS, describe(u, p), __LINE__);
            ASSERT(dn > 0.0 || (p.m1 == 0.0 && std::fabs(u) > 700));
            ASSERT(dn <= 1.0);
        }
}

/** m = 0: sin, cos, 1; m = 1: tanh, sech, sech (DLMF 22.5.3 and 22.5.4). */
void testLimitingParameters() {
    for (double u : argumentGrid()) {
        double sn, cn, dn;
        jacobiElliptic(u, 0.0, 1.0, sn, cn, dn);
        Parameter zero = {0.0, 1.0};
        assertClose(std::sin(u), sn, 2*EPS, describe(u, zero), __LINE__);
        assertClose(std::cos(u), cn, 2*EPS, describe(u, zero), __LINE__);
        assertClose(1.0, dn, 0.0, describe(u, zero), __LINE__);
        jacobiElliptic(u, 1.0, 0.0, sn, cn, dn);
        Parameter one = {1.0, 0.0};
        assertClose(std::tanh(u), sn, 2*EPS, describe(u, one), __LINE__);
        assertRelative(1.0/std::cosh(u), cn, 4*EPS, describe(u, one), __LINE__);
        assertRelative(1.0/std::cosh(u), dn, 4*EPS, describe(u, one), __LINE__);
    }
    // The limits are approached continuously: a tiny m gives sin/cos up to O(m) (DLMF 22.10.1), and
    // m1 = 1e-300 (m rounds to 1, only m1 carries the information) gives tanh/sech up to O(m1).
    for (double u : {0.3, -1.0, 2.5}) {
        double sn, cn, dn;
        jacobiElliptic(u, 1e-300, 1.0, sn, cn, dn);
        assertClose(std::sin(u), sn, 4*EPS, describe(u, {1e-300, 1.0}), __LINE__);
        assertClose(std::cos(u), cn, 4*EPS, describe(u, {1e-300, 1.0}), __LINE__);
        jacobiElliptic(u, 1.0, 1e-300, sn, cn, dn);
        assertClose(std::tanh(u), sn, 4*EPS, describe(u, {1.0, 1e-300}), __LINE__);
        assertRelative(1.0/std::cosh(u), cn, 8*EPS, describe(u, {1.0, 1e-300}), __LINE__);
        assertRelative(1.0/std::cosh(u), dn, 8*EPS, describe(u, {1.0, 1e-300}), __LINE__);
    }
    // Exact zero argument.
    for (const Parameter& p : parameterGrid()) {
        double sn, cn, dn;
        jacobiElliptic(0.0, p.m, p.m1, sn, cn, dn);
        assertClose(0.0, sn, 0.0, describe(0.0, p), __LINE__);
        assertClose(1.0, cn, 0.0, describe(0.0, p), __LINE__);
        assertClose(1.0, dn, EPS, describe(0.0, p), __LINE__);
    }
}

/**
 * Quarter and whole periods (DLMF 22.4.1, 22.4.2): sn(u+4K) = sn(u), cn(u+2K) = -cn(u),
 * dn(u+2K) = dn(u), and sn(K) = 1, cn(K) = 0, dn(K) = sqrt(m1). The budget grows with the size of
 * the shifted argument, since u + 4K is itself rounded.
 */
void testPeriodicity() {
    for (const Parameter& p : parameterGrid()) {
        if (p.m1 == 0.0)
            continue;  // K is infinite
        double K = ellipticK(p.m, p.m1);
        for (double u : argumentGrid()) {
            double tol = 10*EPS*(std::fabs(u) + 4*K + 1);
            double sn, cn, dn, sn4, cn4, dn4, sn2, cn2, dn2;
            jacobiElliptic(u, p.m, p.m1, sn, cn, dn);
            jacobiElliptic(u + 4*K, p.m, p.m1, sn4, cn4, dn4);
            jacobiElliptic(u + 2*K, p.m, p.m1, sn2, cn2, dn2);
            assertClose(sn, sn4, tol, describe(u, p) + " (sn period 4K)", __LINE__);
            assertClose(cn, cn4, tol, describe(u, p) + " (cn period 4K)", __LINE__);
            assertClose(dn, dn4, tol, describe(u, p) + " (dn period 4K)", __LINE__);
            assertClose(-sn, sn2, tol, describe(u, p) + " (sn half period)", __LINE__);
            assertClose(-cn, cn2, tol, describe(u, p) + " (cn half period)", __LINE__);
            assertClose(dn, dn2, tol, describe(u, p) + " (dn period 2K)", __LINE__);
        }
        double sn, cn, dn;
        jacobiElliptic(K, p.m, p.m1, sn, cn, dn);
        double tol = 10*EPS*(K + 1);
        assertClose(1.0, sn, tol, describe(K, p) + " (sn(K) = 1)", __LINE__);
        assertClose(0.0, cn, tol, describe(K, p) + " (cn(K) = 0)", __LINE__);
        assertClose(std::sqrt(p.m1), dn, tol, describe(K, p) + " (dn(K) = sqrt(m1))", __LINE__);
    }
}

/**
 * F(sn(u)|m) = u for |u| <= K (DLMF 22.15.11 with 19.2.4). Near u = +-K the inverse is
 * ill-conditioned: a rounding error dx in x = sn(u) moves F by dx / (cn dn). The budget includes
 * that condition number, and points where it exceeds 1e6 (where sn(u) no longer determines u to
 * better than 1e-10) are skipped.
 */
void testInverse() {
    for (const Parameter& p : parameterGrid()) {
        double K = (p.m1 == 0.0 ? 5.0 : ellipticK(p.m, p.m1));
        for (double s : {-1.0, -0.999, -0.9, -0.5, -0.1, -1e-9, 0.0, 0.2, 0.7, 0.95, 0.9999, 1.0}) {
            double u = s*K;
            double sn, cn, dn;
            jacobiElliptic(u, p.m, p.m1, sn, cn, dn);
            double derivative = std::fabs(cn*dn);
            if (derivative < 1e-6)
                continue;
            double tol = 10*EPS*(1 + std::fabs(u)) + 8*EPS/derivative;
            assertClose(u, ellipticF(sn, p.m, p.m1), tol, describe(u, p) + " (F(sn(u)) = u)", __LINE__);
        }
    }
}

/** K(m) = F(1|m) (DLMF 19.2.8) and K(0) = pi/2. */
void testCompleteIntegral() {
    for (const Parameter& p : parameterGrid()) {
        double K = ellipticK(p.m, p.m1);
        if (p.m1 == 0.0) {
            ASSERT(std::isinf(K) && K > 0);
            continue;
        }
        assertRelative(K, ellipticF(1.0, p.m, p.m1), 8*EPS, describe(1.0, p) + " (K = F(1|m))", __LINE__);
        assertRelative(K, -ellipticF(-1.0, p.m, p.m1), 8*EPS, describe(-1.0, p) + " (K = -F(-1|m))", __LINE__);
    }
    assertRelative(M_PI/2, ellipticK(0.0, 1.0), 2*EPS, "K(0) = pi/2", __LINE__);
}

/**
 * High-precision reference values from mpmath 1.4.1 with mp.dps = 340 (the arguments are the exact
 * binary values of the doubles used below; near m = 1 the parameter is 1 - mpf(m1)):
 *   K:       mpmath.ellipk(mpf(m))                      or mpmath.ellipk(1 - mpf(m1))
 *   F(x|m):  mpmath.ellipf(mpmath.asin(mpf(x)), mpf(m)) or ... , 1 - mpf(m1))
 *   Pi:      mpmath.ellippi(mpf(n), mpmath.asin(mpf(x)), mpf(m))
 *   sn/cn/dn: mpmath.ellipfun('sn', mpf(u), m=mpf(m))   or ... , m=1 - mpf(m1))
 *   RF, RJ:  mpmath.elliprf(x, y, z), mpmath.elliprj(x, y, z, p)
 */
void testReferenceValues() {
    struct Value { double m, m1, expected; };
    // K, generic parameters (m1 = 1 - m rounded as a caller would compute it): 4 ulps relative.
    for (const Value& v : std::vector<Value>{{0.0, 1.0, 1.5707963267948966192},
                                             {1e-10, 1.0 - 1e-10, 1.5707963268341665274},
                                             {0.1, 0.9, 1.6124413487202194007},
                                             {0.5, 0.5, 1.8540746773013719184},
                                             {0.9, 1.0 - 0.9, 2.5780921133481732927},
                                             {0.99, 1.0 - 0.99, 3.6956373629898742386}})
        assertRelative(v.expected, ellipticK(v.m, v.m1), 4*EPS, describe(0, {v.m, v.m1}) + " (K)", __LINE__);
    // K near m = 1 with m1 passed explicitly: 4 ulps relative.
    for (const Value& v : std::vector<Value>{{1.0 - 1e-6, 1e-6, 8.2940514636154400079},
                                             {1.0 - 1e-12, 1e-12, 15.201804919087715184},
                                             {1.0, 1e-20, 24.412145291060347486},
                                             {1.0, 1e-100, 116.51554901082217481},
                                             {1.0, 1e-300, 346.77405831022674321}})
        assertRelative(v.expected, ellipticK(v.m, v.m1), 4*EPS, describe(0, {v.m, v.m1}) + " (K near m = 1)", __LINE__);

    struct Integral { double x, m, m1, expected; };
    // F(x|m), generic and near m = 1: 8 ulps relative.
    for (const Integral& v : std::vector<Integral>{{0.5, 0.3, 0.7, 0.53063689953986742474},
                                                   {0.9, 0.7, 0.3, 1.3044067280954652859},
                                                   {0.999999, 0.5, 0.5, 1.8520746778013424253},
                                                   {-0.3, 0.95, 1.0 - 0.95, -0.30926827600482520333},
                                                   {0.9, 1.0 - 1e-12, 1e-12, 1.4722194895824041912},
                                                   {0.99999, 1.0 - 1e-8, 1e-8, 6.102908862073519807}})
        assertRelative(v.expected, ellipticF(v.x, v.m, v.m1), 8*EPS, describe(v.x, {v.m, v.m1}) + " (F)", __LINE__);

    // Pi(n; x|m): 8 ulps relative (n = -2 costs log10(sqrt(2)) digits at most, well inside).
    struct Third { double n, x, m, expected; };
    for (const Third& v : std::vector<Third>{{0.5, 0.7, 0.3, 0.88356142399795019094},
                                             {-2.0, 0.9, 0.8, 0.86075244427322707764},
                                             {0.9, 0.5, 0.99, 0.60075956383644453555}})
        assertRelative(v.expected, ellipticPi(v.n, v.x, v.m, 1.0 - v.m), 8*EPS,
                       describe(v.x, {v.m, 1.0 - v.m}) + " (Pi, n = " + std::to_string(v.n) + ")", __LINE__);

    // sn, cn, dn: absolute error 8 eps (1 + |u|), the rounding of u included.
    struct Jacobi { double u, m, m1, sn, cn, dn; };
    for (const Jacobi& v : std::vector<Jacobi>{
            {0.7, 0.3, 0.7, 0.63230477631086451725, 0.7747197363269297698, 0.93811363968143021572},
            {2.5, 0.9, 1.0 - 0.9, 0.9996945384505861342, 0.024714971010898662991, 0.31709580068626355582},
            {50.0, 0.9, 1.0 - 0.9, -0.93152040344153682892, 0.36368906771047773849, 0.4680200467660597931},
            {-1.3, 0.5, 0.5, -0.92044647421001782461, 0.39086863280947345889, 0.75920296631215390414},
            {5.0, 1.0 - 1e-10, 1e-10, 0.99990920428757016169, 0.013475280368076983686, 0.013475284077900645536},
            {3.0, 1.0, 1e-300, 0.99505475368673045133, 0.099327927419433207829, 0.099327927419433207829}}) {
        double sn, cn, dn;
        jacobiElliptic(v.u, v.m, v.m1, sn, cn, dn);
        double tol = 8*EPS*(1 + std::fabs(v.u));
        assertClose(v.sn, sn, tol, describe(v.u, {v.m, v.m1}) + " (sn)", __LINE__);
        assertClose(v.cn, cn, tol, describe(v.u, {v.m, v.m1}) + " (cn)", __LINE__);
        assertClose(v.dn, dn, tol, describe(v.u, {v.m, v.m1}) + " (dn)", __LINE__);
    }

    // Carlson integrals: 4 ulps relative.
    assertRelative(0.72694593546890819854, carlsonRF(1, 2, 3), 4*EPS, "RF(1, 2, 3)", __LINE__);
    assertRelative(1.4940949049250779288, carlsonRF(0.5, 2, 1e-3), 4*EPS, "RF(0.5, 2, 1e-3)", __LINE__);
    assertRelative(0.23984809974956776218, carlsonRJ(1, 2, 3, 4), 4*EPS, "RJ(1, 2, 3, 4)", __LINE__);
    assertRelative(0.14297579667156753833, carlsonRJ(2, 3, 4, 5), 4*EPS, "RJ(2, 3, 4, 5)", __LINE__);
}

/**
 * Near m = 1 and for 1 << u < K/2, cn and dn are small (about sech(u)) but well conditioned: their
 * relative condition number with respect to u is |sn dn / cn| <= 1 there, so they are determined to
 * a relative error of order |u| eps. The free rotor relies on this: near its unstable middle axis it
 * evaluates cn and dn at such arguments and feeds cn^2, dn^2 to RF and RJ, whose logarithmic
 * singularity at 0 turns a relative error of cn into an absolute error of the precession angle.
 * Budget: 8 eps (1 + |u|) relative for cn and dn, absolute for sn. Values from mpmath 1.4.1 at
 * mp.dps = 340: mpmath.ellipfun(kind, mpf(u), m=1 - mpf(m1)).
 */
void testRelativeAccuracyNearOne() {
    struct Jacobi { double u, m1, sn, cn, dn; };
    for (const Jacobi& v : std::vector<Jacobi>{
            {9.0, 1e-16, 0.99999996954004099948, 0.00024681960431301303424, 0.00024681960451559012317},
            {12.0, 1e-20, 0.99999999992449730912, 0.000012288424705989071462, 0.000012288424706395958441},
            {17.0, 1e-30, 0.99999999999999657218, 8.2798754375703188264e-8, 8.2798754375703194303e-8},
            {20.0, 1e-100, 0.9999999999999999915, 4.1223072448771156384e-9, 4.1223072448771156384e-9},
            {50.0, 1e-100, 1.0, 3.857499695927835566e-22, 3.857499695927835566e-22},
            {30.0, 1e-300, 1.0, 1.871524593768034921e-13, 1.871524593768034921e-13},
            {150.0, 1e-300, 1.0, 1.435019194632882084e-65, 1.435019194632882084e-65}}) {
        Parameter p = {1.0 - v.m1, v.m1};
        double sn, cn, dn;
        jacobiElliptic(v.u, p.m, p.m1, sn, cn, dn);
        double tol = 8*EPS*(1 + std::fabs(v.u));
        assertClose(v.sn, sn, tol, describe(v.u, p) + " (sn near m = 1)", __LINE__);
        assertRelative(v.cn, cn, tol, describe(v.u, p) + " (cn near m = 1, relative)", __LINE__);
        assertRelative(v.dn, dn, tol, describe(v.u, p) + " (dn near m = 1, relative)", __LINE__);
    }
}

/** Closed forms and symmetries of the Carlson integrals (DLMF 19.20.1, 19.20.5, 19.16.5, 19.16.9). */
void testCarlsonIdentities() {
    for (double x : {1e-100, 1e-10, 0.5, 1.0, 3.0, 1e10, 1e100}) {
        std::string where = "x = " + std::to_string(x);
        assertRelative(1.0/std::sqrt(x), carlsonRF(x, x, x), 4*EPS, where + " (RF(x,x,x))", __LINE__);
        assertRelative(std::pow(x, -1.5), carlsonRJ(x, x, x, x), 4*EPS, where + " (RJ(x,x,x,x))", __LINE__);
        assertRelative(M_PI/(2*std::sqrt(x)), carlsonRF(0, x, x), 4*EPS, where + " (RF(0,x,x))", __LINE__);
    }
    assertRelative(M_PI/2, carlsonRF(0, 1, 1), 4*EPS, "RF(0, 1, 1) = pi/2", __LINE__);
    // Symmetry in the first three arguments and homogeneity of degree -1/2 and -3/2.
    const double x = 0.3, y = 1.7, z = 4.2, p = 0.9;
    double rf = carlsonRF(x, y, z), rj = carlsonRJ(x, y, z, p);
    assertRelative(rf, carlsonRF(z, x, y), 4*EPS, "RF symmetry", __LINE__);
    assertRelative(rf, carlsonRF(y, z, x), 4*EPS, "RF symmetry", __LINE__);
    assertRelative(rj, carlsonRJ(z, x, y, p), 4*EPS, "RJ symmetry", __LINE__);
    assertRelative(rj, carlsonRJ(y, z, x, p), 4*EPS, "RJ symmetry", __LINE__);
    assertRelative(rf/std::sqrt(16.0), carlsonRF(16*x, 16*y, 16*z), 4*EPS, "RF homogeneity", __LINE__);
    assertRelative(rj/64.0, carlsonRJ(16*x, 16*y, 16*z, 16*p), 4*EPS, "RJ homogeneity", __LINE__);
}

/**
 * Legendre's relation E K' + E' K - K K' = pi/2 (DLMF 19.7.1), with E computed from Carlson's
 * integrals only: E(m) = RF(0, m1, 1) - m/3 RD(0, m1, 1) (DLMF 19.25.1), where RD(x, y, z) = RJ(x, y, z, z)
 * (DLMF 19.16.5), and K' = K(m1), E' = E(m1). This ties RF and RJ together independently of mpmath.
 */
void testLegendreRelation() {
    for (double m : {1e-6, 0.1, 0.3, 0.5, 0.7, 0.9, 0.999}) {
        double m1 = 1.0 - m;
        double K = carlsonRF(0, m1, 1), K1 = carlsonRF(0, m, 1);
        double E = K - m/3*carlsonRJ(0, m1, 1, 1);
        double E1 = K1 - m1/3*carlsonRJ(0, m, 1, 1);
        // The three products are each of size K K' <= 13 here; allow 8 ulps of each.
        assertClose(M_PI/2, E*K1 + E1*K - K*K1, 8*EPS*(1 + 3*K*K1), "m = " + std::to_string(m) + " (Legendre)", __LINE__);
        assertRelative(ellipticK(m, m1), K, 4*EPS, "m = " + std::to_string(m) + " (K = RF(0, m1, 1))", __LINE__);
    }
}

/** Pi(0; x|m) = F(x|m) and the m = 0 closed form Pi(n; x|0) = atan(sqrt(1-n) tan(phi))/sqrt(1-n) (DLMF 19.6.11). */
void testThirdKindSpecialCases() {
    for (double x : {-0.8, 0.1, 0.6, 0.99})
        for (const Parameter& p : std::vector<Parameter>{{0.0, 1.0}, {0.4, 0.6}, {1.0 - 1e-9, 1e-9}}) {
            assertRelative(ellipticF(x, p.m, p.m1), ellipticPi(0.0, x, p.m, p.m1), 4*EPS, describe(x, p) + " (Pi(0) = F)", __LINE__);
            for (double n : {-3.0, -0.5, 0.5, 0.9}) {
                if (p.m != 0.0)
                    continue;
                double phi = std::asin(x), s = std::sqrt(1 - n);
                assertRelative(std::atan(s*std::tan(phi))/s, ellipticPi(n, x, 0.0, 1.0), 16*EPS,
                               describe(x, p) + " (Pi at m = 0, n = " + std::to_string(n) + ")", __LINE__);
            }
        }
}

/** Arguments outside the domain are rejected with std::invalid_argument, never returned as NaN. */
void testDomainErrors() {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    double sn, cn, dn;
    assertThrowsInvalidArgument([&]() {jacobiElliptic(1.0, 1.5, -0.5, sn, cn, dn);}, "jacobiElliptic(m = 1.5)", __LINE__);
    assertThrowsInvalidArgument([&]() {jacobiElliptic(1.0, -0.1, 1.1, sn, cn, dn);}, "jacobiElliptic(m = -0.1)", __LINE__);
    assertThrowsInvalidArgument([&]() {jacobiElliptic(1.0, nan, nan, sn, cn, dn);}, "jacobiElliptic(m = NaN)", __LINE__);
    assertThrowsInvalidArgument([&]() {jacobiElliptic(nan, 0.5, 0.5, sn, cn, dn);}, "jacobiElliptic(u = NaN)", __LINE__);
    assertThrowsInvalidArgument([&]() {ellipticK(2.0, -1.0);}, "ellipticK(m = 2)", __LINE__);
    assertThrowsInvalidArgument([&]() {ellipticF(1.5, 0.5, 0.5);}, "ellipticF(x = 1.5)", __LINE__);
    assertThrowsInvalidArgument([&]() {ellipticF(nan, 0.5, 0.5);}, "ellipticF(x = NaN)", __LINE__);
    assertThrowsInvalidArgument([&]() {ellipticPi(1.0, 1.0, 0.5, 0.5);}, "ellipticPi(n x^2 = 1)", __LINE__);
    assertThrowsInvalidArgument([&]() {carlsonRF(-1.0, 1.0, 1.0);}, "carlsonRF(-1, 1, 1)", __LINE__);
    assertThrowsInvalidArgument([&]() {carlsonRF(nan, 1.0, 1.0);}, "carlsonRF(NaN, 1, 1)", __LINE__);
    assertThrowsInvalidArgument([&]() {carlsonRJ(1.0, 1.0, 1.0, 0.0);}, "carlsonRJ(p = 0)", __LINE__);
    assertThrowsInvalidArgument([&]() {carlsonRJ(1.0, 1.0, 1.0, -1.0);}, "carlsonRJ(p = -1)", __LINE__);
}

/** |computed - exact| in units of the spacing of doubles at the exact value (its ulp). */
double ulpsOff(double computed, long double exact) {
    const double rounded = (double) fabsl(exact);
    const double ulp = (rounded == 0.0 ? std::numeric_limits<double>::denorm_min() :
                        std::nextafter(rounded, std::numeric_limits<double>::infinity()) - rounded);
    return (double) (fabsl((long double) computed - exact)/ulp);
}

/**
 * rigidSinCos, the rotor's sine and cosine, against long double sinl and cosl (64-bit significands):
 * within 1 ulp on random arguments of every size up to the limit of its own reduction, next to the
 * multiples of pi/2 (where the reduction cancels), at the quadrant boundaries; beyond the limit, and
 * for infinities and NaN, the library's values exactly; signed zeros and subnormals kept.
 */
void testSinCos() {
    std::vector<double> arguments;
    unsigned long long state = 88172645463325252ULL;
    auto uniform = [&state]() {  // xorshift64, in [0, 1)
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        return (state >> 11)*(1.0/9007199254740992.0);
    };
    for (int i = 0; i < 400000; i++)
        arguments.push_back((2.0*uniform() - 1.0)*M_PI/4);
    for (int i = 0; i < 400000; i++)  // magnitudes 1e-8 to 1e5, both signs
        arguments.push_back((uniform() < 0.5 ? -1.0 : 1.0)*std::pow(10.0, -8.0 + 13.0*uniform()));
    for (int k = -63000; k <= 63000; k += 7) {
        const double nearest = (double) (k*(M_PIl/2));  // the double nearest k pi/2, and its neighbours
        arguments.push_back(nearest);
        arguments.push_back(std::nextafter(nearest, 1e6));
        arguments.push_back(std::nextafter(nearest, -1e6));
        const double boundary = (double) ((k + 0.5L)*(M_PIl/2));  // where the quadrant changes
        arguments.push_back(boundary);
        arguments.push_back(std::nextafter(boundary, 1e6));
    }
    arguments.push_back(RIGID_SIN_COS_LIMIT);
    arguments.push_back(-RIGID_SIN_COS_LIMIT);
    arguments.push_back(1e-310);
    arguments.push_back(-5e-324);
    double worst = 0.0, worstArgument = 0.0;
    for (double x : arguments) {
        double s, c;
        OpenMMRigid::rigidSinCos(x, &s, &c);
        const double off = std::max(ulpsOff(s, sinl((long double) x)), ulpsOff(c, cosl((long double) x)));
        if (off > worst) {
            worst = off;
            worstArgument = x;
        }
    }
    if (!(worst <= 1.0))
        throw std::runtime_error("rigidSinCos is " + std::to_string(worst) + " ulps off at x = " + std::to_string(worstArgument));
    std::cout << "rigidSinCos: largest error " << worst << " ulps over " << arguments.size() << " arguments" << std::endl;
    // Beyond the limit, infinities and NaN: the library's sin and cos.
    const double inf = std::numeric_limits<double>::infinity();
    for (double x : {std::nextafter(RIGID_SIN_COS_LIMIT, inf), -2e5, 1e22, -3.5e300, inf, -inf}) {
        double s, c;
        OpenMMRigid::rigidSinCos(x, &s, &c);
        const double libS = std::sin(x), libC = std::cos(x);
        ASSERT((s == libS && c == libC) || (std::isnan(libS) && std::isnan(s) && std::isnan(c)));
    }
    double s, c;
    OpenMMRigid::rigidSinCos(std::numeric_limits<double>::quiet_NaN(), &s, &c);
    ASSERT(std::isnan(s) && std::isnan(c));
    OpenMMRigid::rigidSinCos(-0.0, &s, &c);
    ASSERT(s == 0.0 && std::signbit(s) && c == 1.0);
    OpenMMRigid::rigidSinCos(0.0, &s, &c);
    ASSERT(s == 0.0 && !std::signbit(s) && c == 1.0);
    OpenMMRigid::rigidSinCos(-5e-324, &s, &c);
    ASSERT(s == -5e-324 && c == 1.0);
}

int main() {
    try {
        testPythagoreanIdentities();
        testLimitingParameters();
        testPeriodicity();
        testInverse();
        testCompleteIntegral();
        testReferenceValues();
        testRelativeAccuracyNearOne();
        testCarlsonIdentities();
        testLegendreRelation();
        testThirdKindSpecialCases();
        testDomainErrors();
        testSinCos();
    }
    catch (const std::exception& e) {
        std::cout << "exception: " << e.what() << std::endl;
        return 1;
    }
    std::cout << "Done" << std::endl;
    return 0;
}
