/* -------------------------------------------------------------------------- *
 *                               OpenMM-Rigid                                 *
 * -------------------------------------------------------------------------- *
 * The numerics core compiled as C (CoreC.c, C99 behind core/CorePreludeC.h)  *
 * against the same text compiled as C++ inside the validating API: FreeRotor *
 * (evolve in every representation, and advance), rigidClassifyMoments,       *
 * Special:: (Jacobi functions, RF, RJ, K), noSquishRotate, philox4x32,       *
 * NormalStream and the Bussi thermostat's factor (rigidStochasticRescaling,  *
 * also against an independent transcription of eqs. (A7) and (A8) and the   *
 * closed forms of its special cases). Bodies of every kind and regime (generic, near and on the    *
 * separatrix, steady rotation about each axis, tiny off-axis components,     *
 * omega = 0, nearly symmetric, moments snapped by the classification,        *
 * subnormal and huge omega), times of both signs up to many periods.         *
 *                                                                            *
 * The two compilations share every line of arithmetic and call the same     *
 * libm, so agreement is required to the last bit.                            *
 * -------------------------------------------------------------------------- */

#include "../RandomRotation.h"
#include "CoreC.h"
#include "numerics/Elliptic.h"
#include "numerics/FreeRotor.h"
#include "numerics/NoSquish.h"
#include "numerics/Philox.h"
#include "numerics/StochasticRescaling.h"
#include "openmm/internal/AssertionUtilities.h"
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <cstring>
#include <iostream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

using namespace OpenMM;
using namespace OpenMMRigid;

static std::mt19937_64 rng(20261201);
static int comparisons = 0;

static double uniform(double low, double high) {
    return std::uniform_real_distribution<double>(low, high)(rng);
}

static double normal() {
    return std::normal_distribution<double>(0.0, 1.0)(rng);
}

/** Fails unless a and b are the same double to the last bit (so -0 differs from +0, and NaN fails). */
static void assertSameBits(double a, double b, const std::string& what, int line) {
    comparisons++;
    if (std::memcmp(&a, &b, sizeof(double)) != 0 || a != a) {
        std::stringstream s;
        s.precision(17);
        s << what << ": C " << b << " vs C++ " << a;
        throwException(__FILE__, line, s.str());
    }
}

struct Body {
    Vector3 moments, omega;
    std::string name;
};

static std::string describe(const Body& body, double t) {
    std::stringstream s;
    s.precision(17);
    s << body.name << ": moments (" << body.moments[0] << ", " << body.moments[1] << ", " << body.moments[2] << "), omega ("
      << body.omega[0] << ", " << body.omega[1] << ", " << body.omega[2] << "), t = " << t;
    return s.str();
}

/** Bodies in every regime of the rotor. */
static std::vector<Body> bodies() {
    std::vector<Body> list;
    for (int n = 0; n < 40; n++) {
        double a = uniform(0.5, 5), b = uniform(0.5, 5), c = uniform(0.5, 5);
        Vector3 omega = {normal(), normal(), normal()};
        int axis = n%3;
        Vector3 linear = {a, a, a}, symmetric = {a, a, a};
        linear[axis] = 0.0;
        symmetric[axis] = b;
        list.push_back({{a, b, c}, omega, "asymmetric " + std::to_string(n)});
        list.push_back({{a, a, a}, omega, "spherical " + std::to_string(n)});
        list.push_back({symmetric, omega, "symmetric " + std::to_string(n)});
        list.push_back({linear, omega, "linear " + std::to_string(n)});
    }
    // On and near the separatrix: I = (1, 5, 9), omega = (3, w2, 1) has L^2 = 2E I2 exactly; offsets
    // of the largest component put the motion just inside or outside it (m just below 1 on either
    // ordering, where the automatic choice takes the elliptic integral).
    for (double w2 : {0.5, 0.0, -2.0})
        list.push_back({{1, 5, 9}, {3, w2, 1}, "separatrix"});
    for (double offset : {1e-3, -1e-3, 1e-6, -1e-6, 1e-12, -1e-12})
        list.push_back({{1, 5, 9}, {3, 0.5, 1 + offset}, "near separatrix"});
    // Steady rotation about each principal axis, tiny off-axis components, omega = 0, turning points.
    for (int axis = 0; axis < 3; axis++)
        for (double small : {0.0, 1e-300, 1e-20, 1e-9}) {
            Vector3 omega = {small, -small, 0.5*small};
            omega[axis] = 1.7;
            list.push_back({{1, 2, 3}, omega, "principal axis " + std::to_string(axis)});
            list.push_back({{3, 1, 2}, omega, "principal axis (cyclic moments) " + std::to_string(axis)});
        }
    list.push_back({{1, 2, 3}, {0, 0, 0}, "omega = 0"});
    list.push_back({{10, 20, 26}, {0.0, 15, 1}, "turning point"});
    list.push_back({{10, 20, 26}, {1, 15, 1}, "paper Section 5"});
    // Nearly symmetric (distinct: m ~ 1e-12) and within the classification's tolerance (snapped).
    list.push_back({{10, 10*(1 + 1e-12), 26}, {0.3, -1.2, 0.8}, "nearly prolate"});
    list.push_back({{10, 26*(1 - 1e-12), 26}, {0.3, -1.2, 0.8}, "nearly oblate"});
    list.push_back({{10, 10*(1 + 2e-14), 26}, {0.3, -1.2, 0.8}, "snapped symmetric"});
    list.push_back({{3, 3*(1 + 2e-14), 3*(1 - 2e-14)}, {0.3, -1.2, 0.8}, "snapped spherical"});
    list.push_back({{1e-15, 2, 2*(1 + 1e-14)}, {0.3, -1.2, 0.8}, "snapped linear"});
    // The ends of the internal frequency scaling.
    list.push_back({{1, 2, 3}, {3e-310, -1e-309, 2e-310}, "subnormal omega"});
    list.push_back({{1, 2, 3}, {1e307, -3e307, 2e306}, "huge omega"});
    return list;
}

static void copyAttitude(const Matrix3& a, double* flat) {
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            flat[3*i + j] = a[i][j];
}

/** evolve() in each representation and advance(), the C core against FreeRotor. */
void testRotor() {
    for (const Body& body : bodies()) {
        Matrix3 attitude = RigidBodyTestSupport::randomRotation(normal);
        double flat[9];
        copyAttitude(attitude, flat);
        double scale = std::max({std::fabs(body.omega[0]), std::fabs(body.omega[1]), std::fabs(body.omega[2]), 1e-300});
        std::vector<double> times = {0.0, 0.03/scale, -0.7/scale, 5.0/scale, 123.0/scale};
        for (int representation : {FreeRotor::Automatic, FreeRotor::ThetaSeries, FreeRotor::EllipticIntegral}) {
            bool thrown = false;
            std::vector<double> omegas(3*times.size()), attitudes(9*times.size());
            double parameter;
            int used;
            int status = coreCEvolve(body.moments.data(), body.omega.data(), flat, representation, times.size(), times.data(),
                                     omegas.data(), attitudes.data(), &parameter, &used);
            try {
                FreeRotor rotor(body.moments, body.omega, attitude, (FreeRotor::Representation) representation);
                ASSERT_EQUAL(used, rotor.getRepresentation());
                assertSameBits(rotor.getParameter(), parameter, "parameter of " + body.name, __LINE__);
                for (size_t n = 0; n < times.size(); n++) {
                    Vector3 omega;
                    Matrix3 a;
                    rotor.evolve(times[n], omega, a);
                    std::string where = describe(body, times[n]) + ", representation " + std::to_string(representation);
                    for (int i = 0; i < 3; i++) {
                        assertSameBits(omega[i], omegas[3*n + i], "evolve omega, " + where, __LINE__);
                        for (int j = 0; j < 3; j++)
                            assertSameBits(a[i][j], attitudes[9*n + 3*i + j], "evolve A, " + where, __LINE__);
                    }
                }
            }
            catch (const std::invalid_argument&) {
                thrown = true;
            }
            // The C status is an error exactly where the C++ API throws (the theta series on the separatrix).
            ASSERT_EQUAL(thrown, status != RigidStatusOk);
        }
        for (double t : times) {
            Vector3 omega = body.omega;
            Matrix3 a = attitude;
            FreeRotor::advance(body.moments, omega, a, t);
            Vector3 omegaC = body.omega;
            double flatC[9];
            copyAttitude(attitude, flatC);
            ASSERT_EQUAL(RigidStatusOk, coreCAdvance(body.moments.data(), omegaC.data(), flatC, t));
            std::string where = describe(body, t);
            for (int i = 0; i < 3; i++) {
                assertSameBits(omega[i], omegaC[i], "advance omega, " + where, __LINE__);
                for (int j = 0; j < 3; j++)
                    assertSameBits(a[i][j], flatC[3*i + j], "advance A, " + where, __LINE__);
            }
        }
    }
}

/**
 * rigidRotorAdvanceLanes compiled as C, against FreeRotor::advance (the C++ scalar path): every group
 * of up to RigidLanes consecutive bodies of the list, the ends of the frequency scaling included.
 */
void testRotorLanes() {
    std::vector<Body> list = bodies();
    const int numBodies = list.size();
    for (int count = 1; count <= RigidLanes; count++)
        for (int first = 0; first + count <= numBodies; first++) {
            const double t = std::vector<double>{0.0, 0.03, -0.7}[first%3];
            std::vector<double> moments(3*count), omega(3*count), attitude(9*count);
            std::vector<Vector3> expectedOmega(count);
            std::vector<Matrix3> expectedAttitude(count);
            for (int b = 0; b < count; b++) {
                const Body& body = list[first + b];
                expectedAttitude[b] = RigidBodyTestSupport::randomRotation(normal);
                expectedOmega[b] = body.omega;
                copyAttitude(expectedAttitude[b], &attitude[9*b]);
                for (int k = 0; k < 3; k++) {
                    moments[3*b + k] = body.moments[k];
                    omega[3*b + k] = body.omega[k];
                }
                FreeRotor::advance(body.moments, expectedOmega[b], expectedAttitude[b], t);
            }
            ASSERT_EQUAL(RigidStatusOk, coreCAdvanceLanes(count, moments.data(), omega.data(), attitude.data(), t));
            for (int b = 0; b < count; b++) {
                std::string where = "lane " + std::to_string(b) + " of " + std::to_string(count) + ", " +
                                    describe(list[first + b], t);
                for (int i = 0; i < 3; i++) {
                    assertSameBits(expectedOmega[b][i], omega[3*b + i], "lanes omega, " + where, __LINE__);
                    for (int j = 0; j < 3; j++)
                        assertSameBits(expectedAttitude[b][i][j], attitude[9*b + 3*i + j], "lanes A, " + where, __LINE__);
                }
            }
        }
}

/** The classification: kinds, unique axes, snapped moments and error statuses, C against C++. */
void testClassification() {
    std::vector<Vector3> cases = {{1, 2, 3}, {2, 2, 2}, {2, 2, 3}, {3, 2, 2}, {2, 3, 2}, {0, 2, 2}, {2, 0, 2}, {2, 2, 0},
                                  {0, 0, 0}, {0, 0, 1}, {0, 1, 2}, {-1, 2, 3}, {1, 2, NAN}, {1, 1 + 1e-12, 3},
                                  {1, 1 + 5e-14, 3}, {1, 1 + 5e-14, 1 - 5e-14}, {1e-14, 1, 1}, {1e-12, 1, 1}};
    for (const Vector3& moments : cases) {
        RigidShape shape;
        int status = rigidClassifyMoments(moments.data(), &shape);
        int kind, uniqueAxis;
        double classified[3];
        ASSERT_EQUAL(status, coreCClassify(moments.data(), &kind, &uniqueAxis, classified));
        if (status != RigidStatusOk)
            continue;
        ASSERT_EQUAL(shape.kind, kind);
        ASSERT_EQUAL(shape.uniqueAxis, uniqueAxis);
        for (int k = 0; k < 3; k++)
            assertSameBits(shape.moments[k], classified[k], "classified moment", __LINE__);
    }
}

/** The elliptic functions of the core, against Special:: (which checks its arguments, then calls the core). */
void testSpecialFunctions() {
    for (double m1 : {1.0, 0.9, 0.5, 0.1, 1e-3, 1e-10, 1e-20, 1e-33, 1e-100, 0.0}) {
        double m = 1.0 - m1;
        assertSameBits(Special::ellipticK(m, m1), coreCEllipticK(m1), "ellipticK", __LINE__);
        for (double u : {0.0, 0.3, -2.5, 30.0, 123.456, -400.0}) {
            double sn, cn, dn, snC, cnC, dnC;
            Special::jacobiElliptic(u, m, m1, sn, cn, dn);
            coreCJacobi(u, m, m1, &snC, &cnC, &dnC);
            assertSameBits(sn, snC, "sn", __LINE__);
            assertSameBits(cn, cnC, "cn", __LINE__);
            assertSameBits(dn, dnC, "dn", __LINE__);
        }
    }
    for (double x : {0.0, 1e-300, 0.5, 2.0, 1e300})
        for (double y : {1e-10, 1.0, 7.0})
            for (double z : {0.3, 1.0, 1e10}) {
                assertSameBits(Special::carlsonRF(x, y, z), coreCCarlsonRF(x, y, z), "RF", __LINE__);
                for (double p : {0.7, 1e-8, 1e8})
                    assertSameBits(Special::carlsonRJ(x, y, z, p), coreCCarlsonRJ(x, y, z, p), "RJ", __LINE__);
            }
}

/** NO_SQUISH, Philox and the normal deviates. */
void testNoSquishAndRandomNumbers() {
    for (const Vector3& moments : std::vector<Vector3>{{1, 2, 3}, {0, 2, 2}, {2, 2, 2}, {3, 1, 1}}) {
        Matrix3 attitude = RigidBodyTestSupport::randomRotation(normal);
        Vector3 l = {normal(), normal(), normal()};
        for (double dt : {0.002, -0.5, 3.0}) {
            Matrix3 a = attitude;
            Vector3 lCpp = l, lC = l;
            double flat[9];
            copyAttitude(attitude, flat);
            noSquishRotate(moments, dt, a, lCpp);
            coreCNoSquish(moments.data(), dt, flat, lC.data());
            for (int i = 0; i < 3; i++) {
                assertSameBits(lCpp[i], lC[i], "NO_SQUISH L", __LINE__);
                for (int j = 0; j < 3; j++)
                    assertSameBits(a[i][j], flat[3*i + j], "NO_SQUISH A", __LINE__);
            }
        }
    }
    for (uint64_t seed : {0ull, 12345ull, 0xFFFFFFFFFFFFFFFFull})
        for (uint32_t stream : {0u, 7u, 0xFFFFFFFFu})
            for (uint64_t step : {0ull, 99ull, 1ull << 40}) {
                NormalStream s(seed, stream, step);
                double normals[11], uniformC;
                coreCNormals(seed, stream, step, 11, normals, &uniformC);
                for (int k = 0; k < 11; k++)
                    assertSameBits(s.next(), normals[k], "normal deviate", __LINE__);
                assertSameBits(s.uniform(), uniformC, "uniform deviate", __LINE__);
            }
    std::array<uint32_t, 4> counter = {0x243f6a88, 0x85a308d3, 0x13198a2e, 0x03707344};
    std::array<uint32_t, 2> key = {0xa4093822, 0x299f31d0};
    std::array<uint32_t, 4> block = philox4x32(counter, key), blockC;
    coreCPhilox(counter.data(), key.data(), blockC.data());
    ASSERT(block == blockC);
}

/** The constants the core writes out are the values its comments derive them from. */
/**
 * Raised moments: rigidRaiseAngularMomentum keeps the angular velocity (A L / I' equals A l / I to
 * rounding, whatever the attitude), leaves l bit for bit when no moment is raised, and gives the same
 * bits in C; rigidRotationalEnergy is sum L_k^2 / (2 I_k) with nothing on a zero moment.
 */
void testRaisedMoments() {
    const Vector3 massMoments = {0.6, 1.2, 1.8};
    for (const Vector3& raised : std::vector<Vector3>{{0.6, 1.2, 1.8}, {4.0, 4.0, 4.0}, {1.2, 1.2, 1.8}, {0.6, 5.0, 9.0}}) {
        Vector3 scale;
        for (int k = 0; k < 3; k++)
            scale[k] = raised[k]/massMoments[k];
        for (int trial = 0; trial < 5; trial++) {
            Matrix3 attitude = RigidBodyTestSupport::randomRotation(normal);
            double a[3][3], flat[9];
            for (int i = 0; i < 3; i++)
                for (int j = 0; j < 3; j++)
                    a[i][j] = attitude[i][j];
            copyAttitude(attitude, flat);
            Vector3 l = {normal(), normal(), normal()};
            Vector3 lCpp = l, lC = l;
            rigidRaiseAngularMomentum(a, scale.data(), lCpp.data());
            coreCRaiseAngularMomentum(flat, scale.data(), lC.data());
            Vector3 before = multiply(attitude, l), after = multiply(attitude, lCpp);
            for (int k = 0; k < 3; k++) {
                assertSameBits(lCpp[k], lC[k], "raised L", __LINE__);
                if (raised == massMoments)
                    assertSameBits(l[k], lCpp[k], "unraised L", __LINE__);
                ASSERT_EQUAL_TOL(before[k]/massMoments[k], after[k]/raised[k], 1e-14);
            }
            double expected = 0.0;
            for (int k = 0; k < 3; k++)
                expected += 0.5*after[k]*after[k]/raised[k];
            ASSERT_EQUAL_TOL(expected, rigidRotationalEnergy(raised.data(), after.data()), 1e-15);
            assertSameBits(rigidRotationalEnergy(raised.data(), after.data()), coreCRotationalEnergy(raised.data(), after.data()),
                           "rotational energy", __LINE__);
        }
    }
    const double linear[3] = {0.0, 2.0, 2.0}, momentum[3] = {5.0, 1.0, -2.0};
    ASSERT_EQUAL_TOL(0.25 + 1.0, rigidRotationalEnergy(linear, momentum), 1e-15);
}

/**
 * The Bussi thermostat's factor, rigidStochasticRescaling (numerics/core/CoreThermostat.h), in each
 * of its regimes: C and C++ give the same bits; the generic case, with alpha of either sign, is
 * eqs. (A7) and (A8) as written out here (the thermostat's host code before the factor moved to the
 * core) to the last bit, with alpha^2 K = K' to rounding; K <= 0, N_f <= 0 and c >= 1 scale nothing
 * (alpha 1, K' = K); Kbar = 0 damps, alpha = sqrt(c) and K' = c K exactly. The C++ wrapper
 * stochasticRescalingFactor is the core applied to the deviates stochasticRescalingDeviates draws,
 * R_1 and then S from the same stream, also where K = 0.
 */
void testStochasticRescaling() {
    auto both = [](double kinetic, double target, int dof, double c, double r1, double rest, double& newKinetic) {
        double newKineticC;
        const double alpha = rigidStochasticRescaling(kinetic, target, dof, c, r1, rest, &newKinetic);
        assertSameBits(alpha, coreCStochasticRescaling(kinetic, target, dof, c, r1, rest, &newKineticC), "alpha", __LINE__);
        assertSameBits(newKinetic, newKineticC, "K'", __LINE__);
        return alpha;
    };
    // Generic: K, Kbar and N_f over decades, c from strong to weak coupling, deviates of both signs.
    int negative = 0;
    for (int trial = 0; trial < 400; trial++) {
        const int dof = 1 + (int) uniform(0, trial%2 == 0 ? 10 : 3000);
        const double target = 0.5*dof*uniform(0.01, 10), kinetic = target*std::exp(uniform(-6, 2));
        const double c = (trial%4 == 0 ? uniform(0.0, 0.05) : uniform(0.0, 1.0)), r1 = 3*normal();
        const double rest = (dof - 1)*uniform(0.5, 1.5);  // S is near its mean, N_f - 1
        double newKinetic;
        const double alpha = both(kinetic, target, dof, c, r1, rest, newKinetic);
        // eqs. (A7) and (A8), independently written
        double expected = c*kinetic + (1.0 - c)*target*(r1*r1 + rest)/dof + 2.0*r1*std::sqrt(c*(1.0 - c)*kinetic*target/dof);
        double expectedAlpha = std::sqrt(expected/kinetic);
        if (r1 + std::sqrt(c*dof*kinetic/((1.0 - c)*target)) < 0.0)
            expectedAlpha = -expectedAlpha;
        assertSameBits(expected, newKinetic, "K' of eq. (A7)", __LINE__);
        assertSameBits(expectedAlpha, alpha, "alpha of eqs. (A7), (A8)", __LINE__);
        ASSERT_EQUAL_TOL(newKinetic, alpha*alpha*kinetic, 1e-14);
        negative += (alpha < 0);
    }
    // A scaling through zero (eq. (A8)): small K, strong coupling, R_1 below -sqrt(c N_f K/((1 - c) Kbar)).
    for (int dof : {1, 4, 50}) {
        const double kinetic = 0.01, target = 10.0*dof, c = 0.1, r1 = -1.5;
        ASSERT(r1 + std::sqrt(c*dof*kinetic/((1.0 - c)*target)) < 0.0);
        double newKinetic;
        const double alpha = both(kinetic, target, dof, c, r1, 0.5*dof, newKinetic);
        ASSERT(alpha < 0.0);
        ASSERT_EQUAL_TOL(newKinetic, alpha*alpha*kinetic, 1e-14);
        negative++;
    }
    ASSERT(negative >= 3);
    // No scaling: K <= 0 (or not a number), N_f <= 0, c >= 1.
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double none[][4] = {{0.0, 5.0, 6, 0.5}, {-2.0, 5.0, 6, 0.5}, {nan, 5.0, 6, 0.5}, {3.0, 5.0, 0, 0.5}, {3.0, 5.0, -2, 0.5},
                              {3.0, 5.0, 6, 1.0}, {3.0, 5.0, 6, 1.5}, {0.0, 0.0, 6, 0.5}};
    for (const auto& values : none) {
        double newKinetic;
        comparisons++;
        const double alpha = rigidStochasticRescaling(values[0], values[1], (int) values[2], values[3], 0.7, 2.0, &newKinetic);
        double newKineticC;
        ASSERT(alpha == 1.0 && coreCStochasticRescaling(values[0], values[1], (int) values[2], values[3], 0.7, 2.0, &newKineticC) == 1.0);
        ASSERT(std::memcmp(&newKinetic, &values[0], sizeof(double)) == 0 && std::memcmp(&newKineticC, &values[0], sizeof(double)) == 0);
    }
    // Kbar = 0 (or below): damping, K' = c K.
    for (double target : {0.0, -1.0})
        for (double c : {0.0, 0.3, 0.999}) {
            double newKinetic;
            const double alpha = both(7.5, target, 6, c, -2.0, 3.0, newKinetic);
            assertSameBits(std::sqrt(c), alpha, "alpha at Kbar = 0", __LINE__);
            assertSameBits(c*7.5, newKinetic, "K' at Kbar = 0", __LINE__);
        }
    // The wrapper: the deviates R_1 then S (chi-squared, N_f - 1), drawn whenever N_f > 0 and c < 1.
    for (int dof : {1, 2, 33, 400})
        for (double kinetic : {0.0, 12.0}) {
            NormalStream random(99, dof, 3), copy(99, dof, 3);
            double newKinetic, newKineticCore;
            const double alpha = stochasticRescalingFactor(kinetic, 0.5*dof*2.5, dof, 0.8, random, newKinetic);
            const double r1 = copy.next(), rest = chiSquaredDeviate(dof - 1, copy);
            assertSameBits(rigidStochasticRescaling(kinetic, 0.5*dof*2.5, dof, 0.8, r1, rest, &newKineticCore), alpha, "wrapper alpha", __LINE__);
            assertSameBits(newKineticCore, newKinetic, "wrapper K'", __LINE__);
            assertSameBits(copy.next(), random.next(), "the stream after the deviates", __LINE__);
        }
    NormalStream unused(99, 0, 0), fresh(99, 0, 0);
    double r1 = -1.0, rest = -1.0;
    stochasticRescalingDeviates(0, 0.5, unused, r1, rest);
    stochasticRescalingDeviates(6, 1.0, unused, r1, rest);
    ASSERT(r1 == 0.0 && rest == 0.0);
    assertSameBits(fresh.next(), unused.next(), "no deviates drawn for N_f = 0 or c = 1", __LINE__);
}

void testCoreConstants() {
    volatile double eps = std::numeric_limits<double>::epsilon();  // volatile: computed at run time, as the old code did
    assertSameBits(std::pow(3.0*eps, -1.0/8.0), rigidRFStopFactor(), "RF stop factor", __LINE__);
    assertSameBits(std::pow(0.25*eps, -1.0/6.0), rigidRJStopFactor(), "RJ stop factor", __LINE__);
    assertSameBits(M_PI, rigidPi(), "pi", __LINE__);
    assertSameBits(eps, rigidEpsilon(), "epsilon", __LINE__);
    assertSameBits(FreeRotor::automaticThetaSeriesLimit, rigidAutomaticThetaSeriesLimit(), "theta-series limit", __LINE__);
}

int main() {
    try {
        testCoreConstants();
        testClassification();
        testRotor();
        testRotorLanes();
        testSpecialFunctions();
        testNoSquishAndRandomNumbers();
        testRaisedMoments();
        testStochasticRescaling();
        std::cout << comparisons << " values identical in C and C++" << std::endl;
    }
    catch (const std::exception& e) {
        std::cout << "exception: " << e.what() << std::endl;
        return 1;
    }
    std::cout << "Done" << std::endl;
    return 0;
}
