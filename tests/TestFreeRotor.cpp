/* -------------------------------------------------------------------------- *
 *                               OpenMM-Rigid                                 *
 * -------------------------------------------------------------------------- *
 * Tests of the exact free rigid rotor, numerics/FreeRotor.h (van Zon and     *
 * Schofield, J. Comput. Phys. 225 (2007) 145).                               *
 *                                                                            *
 * Every check compares against something known: the paper's Section 5        *
 * example (reference values from a DOP853 integration at rtol 1e-14, see     *
 * docs/free-rotor-notes.md), an independent fourth-order Runge-Kutta         *
 * integration of Euler's equations and dA/dt = -W(omega) A done here with a  *
 * step small enough that its error is below 1e-12, closed forms              *
 * (steady rotation about a principal axis), conservation laws, and the group *
 * properties of an exact flow (composition, time reversal, scaling).         *
 *                                                                            *
 * Tolerances: omega errors are relative to |omega(0)|, attitude errors are   *
 * absolute entries of A. Where a tolerance grows with |omega t| it is the    *
 * phase error (rotation angle) x eps that is inherent in rounding t.         *
 * -------------------------------------------------------------------------- */

#include "RandomRotation.h"
#include "internal/RotorLanes.h"
#include "numerics/FreeRotor.h"
#include "numerics/SymmetricEigen.h"
#include "openmm/internal/AssertionUtilities.h"
#include <algorithm>
#include <cmath>
#include <cstring>
#include <iostream>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

using namespace OpenMM;
using namespace OpenMMRigid;

/** An initial state, with a name that says where it came from (printed when a check fails). */
struct Body {
    Vector3 moments, omega;
    Matrix3 attitude;
    std::string name;
};

struct State {
    Vector3 omega;
    Matrix3 attitude;
};

static std::mt19937_64 rng(20070145);

static double uniform(double low, double high) {
    return std::uniform_real_distribution<double>(low, high)(rng);
}

static double normal() {
    return std::normal_distribution<double>(0.0, 1.0)(rng);
}

/** A short, exact-enough rendering of a number for names and messages ("1e-300", not to_string's "0.000000"). */
static std::string str(double x) {
    std::stringstream s;
    s << x;
    return s.str();
}

static std::string format(const Vector3& v) {
    std::stringstream s;
    s.precision(17);
    s << "(" << v[0] << ", " << v[1] << ", " << v[2] << ")";
    return s.str();
}

static std::string format(const Matrix3& a) {
    return "[" + format(Vector3{a[0][0], a[0][1], a[0][2]}) + ", " + format(Vector3{a[1][0], a[1][1], a[1][2]}) +
           ", " + format(Vector3{a[2][0], a[2][1], a[2][2]}) + "]";
}

/** Everything needed to reproduce a failure. */
static std::string describe(const Body& body, double t) {
    std::stringstream s;
    s.precision(17);
    s << body.name << ": moments " << format(body.moments) << ", omega " << format(body.omega) << ", attitude "
      << format(body.attitude) << ", t = " << t;
    return s.str();
}

/** Fails, naming the check and the input, when !(error <= tol) (so NaN fails). */
static void assertSmall(double error, double tol, const std::string& what, const std::string& where, int line) {
    if (!(error <= tol)) {
        std::stringstream details;
        details.precision(3);
        details << what << ": error " << error << " exceeds " << tol << " for " << where;
        throwException(__FILE__, line, details.str());
    }
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

static double vectorNorm(const Vector3& v) {
    return std::sqrt(v[0]*v[0] + v[1]*v[1] + v[2]*v[2]);
}

static double maxDifference(const Vector3& a, const Vector3& b) {
    return std::max({std::fabs(a[0] - b[0]), std::fabs(a[1] - b[1]), std::fabs(a[2] - b[2])});
}

static double maxDifference(const Matrix3& a, const Matrix3& b) {
    double worst = 0.0;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            worst = std::max(worst, std::fabs(a[i][j] - b[i][j]));
    return worst;
}

static Matrix3 product(const Matrix3& a, const Matrix3& b) {
    Matrix3 c;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            c[i][j] = a[i][0]*b[0][j] + a[i][1]*b[1][j] + a[i][2]*b[2][j];
    return c;
}

/** max |A A^T - 1| and max |A^T A - 1|. */
static double orthonormality(const Matrix3& a) {
    double worst = 0.0;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            double rows = a[i][0]*a[j][0] + a[i][1]*a[j][1] + a[i][2]*a[j][2];
            double columns = a[0][i]*a[0][j] + a[1][i]*a[1][j] + a[2][i]*a[2][j];
            double target = (i == j ? 1.0 : 0.0);
            worst = std::max({worst, std::fabs(rows - target), std::fabs(columns - target)});
        }
    return worst;
}

static double det(const Matrix3& a) {
    return a[0][0]*(a[1][1]*a[2][2] - a[1][2]*a[2][1]) - a[0][1]*(a[1][0]*a[2][2] - a[1][2]*a[2][0]) +
           a[0][2]*(a[1][0]*a[2][1] - a[1][1]*a[2][0]);
}

static double kineticEnergy(const Vector3& moments, const Vector3& omega) {
    return 0.5*(moments[0]*omega[0]*omega[0] + moments[1]*omega[1]*omega[1] + moments[2]*omega[2]*omega[2]);
}

static Vector3 bodyAngularMomentum(const Vector3& moments, const Vector3& omega) {
    return {moments[0]*omega[0], moments[1]*omega[1], moments[2]*omega[2]};
}

/** L_lab = A^T L_body, conserved in free motion. */
static Vector3 labAngularMomentum(const Vector3& moments, const State& state) {
    Vector3 l = bodyAngularMomentum(moments, state.omega);
    const Matrix3& a = state.attitude;
    return {a[0][0]*l[0] + a[1][0]*l[1] + a[2][0]*l[2], a[0][1]*l[0] + a[1][1]*l[1] + a[2][1]*l[2],
            a[0][2]*l[0] + a[1][2]*l[1] + a[2][2]*l[2]};
}

/** exp(W(x)) by Rodrigues' formula, written out here so that the steady-rotation check is independent. */
static Matrix3 rodrigues(const Vector3& x) {
    double angle = vectorNorm(x);
    Matrix3 r = {{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
    if (angle == 0.0)
        return r;
    Vector3 k = {x[0]/angle, x[1]/angle, x[2]/angle};
    Matrix3 w = {{{0, -k[2], k[1]}, {k[2], 0, -k[0]}, {-k[1], k[0], 0}}};
    Matrix3 w2 = product(w, w);
    double s = std::sin(angle), versine = 2*std::sin(0.5*angle)*std::sin(0.5*angle);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            r[i][j] += s*w[i][j] + versine*w2[i][j];
    return r;
}

static Vector3 randomOmega() {
    double scale = std::exp(uniform(std::log(0.1), std::log(10.0)));
    return {scale*normal(), scale*normal(), scale*normal()};
}

/** The rotor of a body; a constructor exception is reported with the input that caused it. */
static FreeRotor makeRotor(const Body& body, FreeRotor::Representation representation = FreeRotor::Automatic) {
    try {
        return FreeRotor(body.moments, body.omega, body.attitude, representation);
    }
    catch (const std::exception& e) {
        std::stringstream s;
        s.precision(17);
        s << "constructor threw \"" << e.what() << "\" for " << body.name << ": moments " << body.moments[0] << " "
          << body.moments[1] << " " << body.moments[2] << ", omega " << body.omega[0] << " " << body.omega[1] << " "
          << body.omega[2] << ", representation " << representation;
        throw std::runtime_error(s.str());
    }
}

static State evolve(const FreeRotor& rotor, double t) {
    State state;
    rotor.evolve(t, state.omega, state.attitude);
    return state;
}

// -------------------------------------------------------------------------------------------------
// Bodies of every kind

/** Random bodies of one kind (FreeRotor::Kind), moments in [0.5, 5] in a random order. */
static std::vector<Body> randomBodies(FreeRotor::Kind kind, int count) {
    std::vector<Body> bodies;
    for (int n = 0; n < count; n++) {
        Body body;
        double a = uniform(0.5, 5.0), b = uniform(0.5, 5.0), c = uniform(0.5, 5.0);
        int axis = std::uniform_int_distribution<int>(0, 2)(rng);
        switch (kind) {
        case FreeRotor::Linear:
            body.moments = {a, a, a};
            body.moments[axis] = 0.0;
            break;
        case FreeRotor::Spherical:
            body.moments = {a, a, a};
            break;
        case FreeRotor::Symmetric:
            while (std::fabs(b - a) < 0.2)
                b = uniform(0.5, 5.0);
            body.moments = {a, a, a};
            body.moments[axis] = b;
            break;
        case FreeRotor::Asymmetric:
            while (std::fabs(b - a) < 0.2)
                b = uniform(0.5, 5.0);
            while (std::fabs(c - a) < 0.2 || std::fabs(c - b) < 0.2)
                c = uniform(0.5, 5.0);
            body.moments = {a, b, c};
            break;
        }
        body.omega = randomOmega();
        body.attitude = RigidBodyTestSupport::randomRotation(normal);
        body.name = std::string("random ") + FreeRotor::kindName(kind) + " body " + std::to_string(n);
        bodies.push_back(body);
    }
    return bodies;
}

/** A moment order with the middle moment first, second or third, for the special cases below. */
static const std::vector<Vector3> ASYMMETRIC_MOMENTS = {{1.0, 2.0, 3.0}, {3.0, 2.0, 1.0}, {2.0, 1.0, 3.0},
                                                        {1.0, 3.0, 2.0}, {10.0, 20.0, 26.0}, {0.6, 4.7, 1.3}};

/**
 * omega that puts the body at (L^2 - 2E I_middle) / L^2 = offset (0 is the separatrix) by solving for
 * the component along the largest moment, keeping the other two.
 */
static Vector3 nearSeparatrixOmega(const Vector3& moments, Vector3 omega, double offset) {
    int order[3] = {0, 1, 2};
    std::sort(order, order + 3, [&](int i, int j) { return moments[i] < moments[j]; });
    int a = order[0], b = order[1], c = order[2];
    double ia = moments[a], ib = moments[b], ic = moments[c];
    double wa = omega[a], wb = omega[b];
    double numerator = offset*(ia*ia*wa*wa + ib*ib*wb*wb) + ia*wa*wa*(ib - ia);
    double denominator = ic*(ic - ib) - offset*ic*ic;
    omega[c] = std::copysign(std::sqrt(numerator/denominator), omega[c]);
    return omega;
}

/** Delicate inputs of the asymmetric top (docs/free-rotor-notes.md, "Where the formulas are delicate"). */
static std::vector<Body> delicateBodies() {
    std::vector<Body> bodies;
    Matrix3 identity = {{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
    // Exactly on the separatrix, in exact arithmetic on these doubles: I = (1, 5, 9), omega = (3, w2, 1)
    // gives L^2 - 2E I2 = 1*9*(1 - 5) + 9*1*(9 - 5) = 0 for any w2.
    bodies.push_back({{1, 5, 9}, {3, 0.5, 1}, identity, "exact separatrix"});
    bodies.push_back({{9, 5, 1}, {1, -0.5, 3}, RigidBodyTestSupport::randomRotation(normal), "exact separatrix, reversed moments"});
    bodies.push_back({{5, 9, 1}, {0.5, 1, -3}, RigidBodyTestSupport::randomRotation(normal), "exact separatrix, cyclic moments"});
    bodies.push_back({{1, 5, 9}, {3, 0, 1}, RigidBodyTestSupport::randomRotation(normal), "exact separatrix, on the homoclinic orbit's midpoint"});
    // Close to the separatrix on either side.
    for (double offset : {1e-3, -1e-3, 1e-8, -1e-8, 1e-14, -1e-14}) {
        Vector3 moments = {1.3, 2.9, 4.1};
        Vector3 omega = nearSeparatrixOmega(moments, {0.7, -1.1, 0.9}, offset);
        bodies.push_back({moments, omega, RigidBodyTestSupport::randomRotation(normal), "near separatrix, offset " + str(offset)});
    }
    // At and near the turning points of the periodic orbit, where omega_1 = 0 and sn(eps) = +-1.
    for (double small : {0.0, 1e-300, 1e-100, 1e-12, 1e-8, -1e-8, 1e-6, 1e-4}) {
        bodies.push_back({{10, 20, 26}, {small, 15, 1}, RigidBodyTestSupport::randomRotation(normal), "turning point, omega_1 = " + str(small)});
        bodies.push_back({{26, 20, 10}, {1, -15, small}, RigidBodyTestSupport::randomRotation(normal), "turning point (reversed), omega_3 = " + str(small)});
    }
    // Close to, and exactly on, the principal axes (steady rotation about the smallest, middle and largest).
    for (const Vector3& moments : ASYMMETRIC_MOMENTS)
        for (int axis = 0; axis < 3; axis++)
            for (double small : {0.0, 1e-100, 1e-20, 1e-9}) {
                Vector3 omega = {small, -small, 0.5*small};
                omega[axis] = 1.7;
                bodies.push_back({moments, omega, RigidBodyTestSupport::randomRotation(normal),
                                  "principal axis " + std::to_string(axis) + " with off-axis " + str(small)});
            }
    // Exactly one zero component (sgn(0) in eqs. (3.36)-(3.39)), and omega = 0.
    bodies.push_back({{1, 2, 3}, {0.0, 1.0, 2.0}, RigidBodyTestSupport::randomRotation(normal), "omega_1 = 0"});
    bodies.push_back({{1, 2, 3}, {1.0, 0.0, 2.0}, RigidBodyTestSupport::randomRotation(normal), "omega_2 = 0"});
    bodies.push_back({{1, 2, 3}, {1.0, 2.0, 0.0}, RigidBodyTestSupport::randomRotation(normal), "omega_3 = 0"});
    bodies.push_back({{1, 2, 3}, {0.0, 0.0, 0.0}, RigidBodyTestSupport::randomRotation(normal), "omega = 0"});
    // Nearly symmetric and nearly spherical (moments equal to 1e-12 relative): m tends to 0.
    bodies.push_back({{10, 10*(1 + 1e-12), 26}, {0.3, -1.2, 0.8}, RigidBodyTestSupport::randomRotation(normal), "nearly prolate"});
    bodies.push_back({{10, 26*(1 - 1e-12), 26}, {0.3, -1.2, 0.8}, RigidBodyTestSupport::randomRotation(normal), "nearly oblate"});
    bodies.push_back({{10, 10*(1 + 1e-12), 10*(1 + 2e-12)}, {0.3, -1.2, 0.8}, RigidBodyTestSupport::randomRotation(normal), "nearly spherical"});
    return bodies;
}

static std::vector<Body> allBodies(int countPerKind) {
    std::vector<Body> bodies;
    for (FreeRotor::Kind kind : {FreeRotor::Linear, FreeRotor::Spherical, FreeRotor::Symmetric, FreeRotor::Asymmetric}) {
        std::vector<Body> some = randomBodies(kind, countPerKind);
        bodies.insert(bodies.end(), some.begin(), some.end());
    }
    std::vector<Body> delicate = delicateBodies();
    bodies.insert(bodies.end(), delicate.begin(), delicate.end());
    return bodies;
}

/** omega with the component along the zero moment of a linear body removed (what the rotor keeps). */
static Vector3 effectiveOmega(const Body& body) {
    Vector3 omega = body.omega;
    for (int k = 0; k < 3; k++)
        if (body.moments[k] == 0.0)
            omega[k] = 0.0;
    return omega;
}

/** |omega(0)|, or 1 when it is zero, to make omega errors relative. */
static double omegaScale(const Body& body) {
    double n = vectorNorm(effectiveOmega(body));
    return n > 0.0 ? n : 1.0;
}

/**
 * The longest |t| over which a comparison of two nearby trajectories is well conditioned. Near the
 * separatrix the motion approaches the unstable middle axis, where any perturbation (the rounding of
 * a restart state included) grows like exp(lambda t), lambda = (L/I2) sqrt((I2-I1)(I3-I2)/(I1 I3)).
 * For bodies within 1e-2 of the separatrix, comparisons are limited to lambda |t| <= 6 (growth 400);
 * elsewhere the growth is polynomial and there is no limit.
 */
static double conditionedTime(const Body& body) {
    const Vector3& i = body.moments;
    if (i[0] == 0 || i[1] == 0 || i[2] == 0 || i[0] == i[1] || i[1] == i[2] || i[0] == i[2])
        return std::numeric_limits<double>::infinity();
    double sorted[3] = {i[0], i[1], i[2]};
    std::sort(sorted, sorted + 3);
    double l2 = 0.0, offset = 0.0;
    for (int k = 0; k < 3; k++) {
        double weight = i[k]*body.omega[k]*body.omega[k];
        l2 += weight*i[k];
        offset += weight*(i[k] - sorted[1]);  // L^2 - 2E I2
    }
    if (l2 == 0.0 || std::fabs(offset) > 1e-2*l2)
        return std::numeric_limits<double>::infinity();
    double lambda = std::sqrt(l2)/sorted[1]*std::sqrt((sorted[1] - sorted[0])*(sorted[2] - sorted[1])/(sorted[0]*sorted[2]));
    return 6.0/lambda;
}

static double clampTime(double t, const Body& body) {
    double limit = conditionedTime(body);
    return std::max(-limit, std::min(limit, t));
}

// -------------------------------------------------------------------------------------------------
// An independent reference: classical RK4 on Euler's equations and dA/dt = -W(omega) A

static void derivative(const Vector3& moments, const State& s, State& d) {
    const Vector3& w = s.omega;
    for (int k = 0; k < 3; k++) {
        int k1 = (k + 1)%3, k2 = (k + 2)%3;
        // I_k dw_k/dt = (I_k1 - I_k2) w_k1 w_k2; a zero moment (linear body) has no dynamics of its own.
        d.omega[k] = (moments[k] == 0.0 ? 0.0 : (moments[k1] - moments[k2])*w[k1]*w[k2]/moments[k]);
    }
    // -W(w) A: column j is -(w x A[:, j]).
    for (int j = 0; j < 3; j++) {
        Vector3 c = {s.attitude[0][j], s.attitude[1][j], s.attitude[2][j]};
        d.attitude[0][j] = -(w[1]*c[2] - w[2]*c[1]);
        d.attitude[1][j] = -(w[2]*c[0] - w[0]*c[2]);
        d.attitude[2][j] = -(w[0]*c[1] - w[1]*c[0]);
    }
}

static State axpy(const State& s, double h, const State& d) {
    State r;
    for (int i = 0; i < 3; i++) {
        r.omega[i] = s.omega[i] + h*d.omega[i];
        for (int j = 0; j < 3; j++)
            r.attitude[i][j] = s.attitude[i][j] + h*d.attitude[i][j];
    }
    return r;
}

/**
 * RK4 from t = 0 through the given (increasing, positive) times. The step is 2e-3 / lambda with
 * lambda = |omega| max(1, Imax/Imin) the fastest rate in the equations, so the local error
 * (h lambda)^5 / 120 ~ 3e-16 and the global error stays near 1e-12 over tens of radians.
 */
static std::vector<State> integrate(const Body& body, const std::vector<double>& times) {
    State s = {effectiveOmega(body), body.attitude};
    double largest = std::max({body.moments[0], body.moments[1], body.moments[2]}), smallest = largest;
    for (double moment : body.moments)
        if (moment > 0.0)
            smallest = std::min(smallest, moment);
    double rate = vectorNorm(s.omega)*std::max(1.0, largest/smallest);
    std::vector<State> result;
    double t = 0.0;
    for (double target : times) {
        int steps = (int) std::ceil((target - t)*rate/2e-3) + 1;
        double h = (target - t)/steps;
        for (int n = 0; n < steps; n++) {
            State k1, k2, k3, k4;
            derivative(body.moments, s, k1);
            derivative(body.moments, axpy(s, 0.5*h, k1), k2);
            derivative(body.moments, axpy(s, 0.5*h, k2), k3);
            derivative(body.moments, axpy(s, h, k3), k4);
            for (int i = 0; i < 3; i++) {
                s.omega[i] += h/6*(k1.omega[i] + 2*k2.omega[i] + 2*k3.omega[i] + k4.omega[i]);
                for (int j = 0; j < 3; j++)
                    s.attitude[i][j] += h/6*(k1.attitude[i][j] + 2*k2.attitude[i][j] + 2*k3.attitude[i][j] + k4.attitude[i][j]);
            }
        }
        t = target;
        result.push_back(s);
    }
    return result;
}

// -------------------------------------------------------------------------------------------------
// Tests

/** The paper's Section 5 example against the DOP853 reference values in the notes (trusted to ~1e-11). */
void testPaperExample() {
    Body body = {{10, 20, 26}, {1, 15, 1}, {{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}}, "paper Section 5"};
    FreeRotor rotor = makeRotor(body);
    ASSERT_EQUAL(FreeRotor::Asymmetric, rotor.getKind());
    ASSERT_EQUAL_TOL(0.5*(10 + 20*225 + 26), rotor.getEnergy(), 1e-15);
    Vector3 l = rotor.getAngularMomentum();
    ASSERT_EQUAL_TOL(10.0, l[0], 1e-15);
    ASSERT_EQUAL_TOL(300.0, l[1], 1e-15);
    ASSERT_EQUAL_TOL(26.0, l[2], 1e-15);
    struct Reference { double t; Vector3 omega; Matrix3 attitude; };
    std::vector<Reference> references = {
        {1.0, {-3.82816674585263, -14.38031707420242, 3.12299788521524},
         {{{-0.04774788417409, -0.03951390794745, -0.99807754740582},
           {-0.29760763575414, -0.95327227334549, 0.05197757219765},
           {-0.95349348959378, 0.29951731827968, 0.03375709337043}}}},
        {10.0, {-8.93297814786449, 10.95152357192214, 7.17715832766704},
         {{{0.34695161257479, -0.38350804757471, 0.85588910261618},
           {0.70961805857052, 0.70403757099296, 0.02780844441733},
           {-0.61324284706982, 0.59770617871641, 0.51641120673539}}}}};
    for (FreeRotor::Representation representation : {FreeRotor::Automatic, FreeRotor::ThetaSeries, FreeRotor::EllipticIntegral}) {
        FreeRotor r = makeRotor(body, representation);
        for (const Reference& reference : references) {
            State state = evolve(r, reference.t);
            std::string where = describe(body, reference.t) + " (representation " + std::to_string(representation) + ")";
            for (int i = 0; i < 3; i++) {
                // ASSERT_EQUAL_TOL semantics: relative to max(1, |expected|).
                assertSmall(std::fabs(state.omega[i] - reference.omega[i])/std::max(1.0, std::fabs(reference.omega[i])),
                            1e-10, "omega vs DOP853", where, __LINE__);
                for (int j = 0; j < 3; j++)
                    assertSmall(std::fabs(state.attitude[i][j] - reference.attitude[i][j]), 1e-10, "A vs DOP853", where, __LINE__);
            }
        }
    }
}

/** Kind, representation, parameter and invariants reported by the accessors. */
void testAccessors() {
    for (const Body& body : allBodies(5)) {
        FreeRotor rotor = makeRotor(body);
        std::string where = describe(body, 0.0);
        int zeros = 0, distinct = 3;
        for (int k = 0; k < 3; k++)
            zeros += (body.moments[k] == 0.0);
        if (body.moments[0] == body.moments[1] || body.moments[1] == body.moments[2] || body.moments[0] == body.moments[2])
            distinct = (body.moments[0] == body.moments[1] && body.moments[1] == body.moments[2] ? 1 : 2);
        FreeRotor::Kind expected = (zeros == 1 ? FreeRotor::Linear : distinct == 1 ? FreeRotor::Spherical :
                                    distinct == 2 ? FreeRotor::Symmetric : FreeRotor::Asymmetric);
        if (rotor.getKind() != expected)
            throwException(__FILE__, __LINE__, "kind " + std::string(FreeRotor::kindName(rotor.getKind())) + " for " + where);
        Vector3 omega = effectiveOmega(body);
        // Steady rotation about a principal axis (or omega = 0) needs no representation; otherwise an
        // asymmetric top reports the one it uses and the other kinds report Automatic.
        bool steady = (omega[0] == 0.0) + (omega[1] == 0.0) + (omega[2] == 0.0) >= 2;
        bool usesRepresentation = (rotor.getKind() == FreeRotor::Asymmetric && !steady);
        if ((rotor.getRepresentation() != FreeRotor::Automatic) != usesRepresentation)
            throwException(__FILE__, __LINE__, "representation " + std::to_string(rotor.getRepresentation()) + " for " + where);
        assertSmall(maxDifference(omega, rotor.getOmega()), 0.0, "getOmega", where, __LINE__);
        assertSmall(maxDifference(body.moments, rotor.getMoments()), 0.0, "getMoments", where, __LINE__);
        assertSmall(maxDifference(body.attitude, rotor.getAttitude()), 0.0, "getAttitude", where, __LINE__);
        double energy = kineticEnergy(body.moments, omega);
        assertSmall(std::fabs(rotor.getEnergy() - energy), 4e-16*energy, "getEnergy", where, __LINE__);
        assertSmall(maxDifference(bodyAngularMomentum(body.moments, omega), rotor.getAngularMomentum()), 0.0,
                    "getAngularMomentum", where, __LINE__);
        if (expected != FreeRotor::Asymmetric) {
            assertSmall(rotor.getParameter(), 0.0, "getParameter of a non-asymmetric rotor", where, __LINE__);
            continue;
        }
        // m from vZS eq. (3.40) in the sorted moments (I_a < I_b < I_c), each L^2 - 2E I written as
        // sum_k I_k w_k^2 (I_k - I) to avoid cancellation; the Jacobi ordering picks m or 1/m (eq. (3.32)).
        int order[3] = {0, 1, 2};
        std::sort(order, order + 3, [&](int i, int j) { return body.moments[i] < body.moments[j]; });
        double ia = body.moments[order[0]], ib = body.moments[order[1]], ic = body.moments[order[2]];
        double da = 0.0, dc = 0.0;
        for (int k = 0; k < 3; k++) {
            double weight = body.moments[k]*omega[k]*omega[k];
            da += weight*(body.moments[k] - ia);
            dc += weight*(body.moments[k] - ic);
        }
        if (steady || da == 0.0)
            continue;  // the rotor uses steady rotation and need not compute m
        double m = dc*(ia - ib)/(da*(ic - ib));
        if (m > 1.0)
            m = 1.0/m;
        assertSmall(std::fabs(rotor.getParameter() - m), 1e-13*std::max(m, 1e-300) + 1e-300, "getParameter", where, __LINE__);
        const double limit = FreeRotor::automaticThetaSeriesLimit;
        FreeRotor::Representation automatic = (m <= limit ? FreeRotor::ThetaSeries : FreeRotor::EllipticIntegral);
        if (std::fabs(m - limit) > 1e-12 && rotor.getRepresentation() != automatic)
            throwException(__FILE__, __LINE__, "unexpected automatic representation for " + where);
    }
    ASSERT_EQUAL(std::string("linear"), std::string(FreeRotor::kindName(FreeRotor::Linear)));
    ASSERT_EQUAL(std::string("spherical"), std::string(FreeRotor::kindName(FreeRotor::Spherical)));
    ASSERT_EQUAL(std::string("symmetric"), std::string(FreeRotor::kindName(FreeRotor::Symmetric)));
    ASSERT_EQUAL(std::string("asymmetric"), std::string(FreeRotor::kindName(FreeRotor::Asymmetric)));
}

/** evolve(0) returns the initial state (to rounding) for every body, the delicate ones included. */
void testInitialState() {
    for (const Body& body : allBodies(10))
        for (FreeRotor::Representation representation : {FreeRotor::Automatic, FreeRotor::EllipticIntegral}) {
            FreeRotor rotor = makeRotor(body, representation);
            State state = evolve(rotor, 0.0);
            std::string where = describe(body, 0.0) + " (representation " + std::to_string(rotor.getRepresentation()) + ")";
            assertSmall(maxDifference(effectiveOmega(body), state.omega)/omegaScale(body), 1e-13, "omega(0)", where, __LINE__);
            assertSmall(maxDifference(body.attitude, state.attitude), 1e-13, "A(0)", where, __LINE__);
        }
}

/**
 * A stays orthonormal with determinant +1 (1e-13), and E and |L| are conserved to 1e-13 relative, at
 * times from 1e-7 to 1000 rotation periods' worth of angle and of either sign. L_lab = A^T L_body is
 * conserved too, to 1e-13 (10 + |omega t|): it depends on the phase of A, whose error grows like the angle.
 */
void testConservation() {
    for (const Body& body : allBodies(40)) {
        FreeRotor rotor = makeRotor(body);
        Vector3 omega0 = effectiveOmega(body);
        double energy = kineticEnergy(body.moments, omega0);
        double l = vectorNorm(bodyAngularMomentum(body.moments, omega0));
        Vector3 lab = labAngularMomentum(body.moments, {omega0, body.attitude});
        double scale = omegaScale(body);
        for (double angle : {0.0, 1e-7, 0.01, 0.3, 1.7, 6.1, 19.9, -3.3, -27.0, 137.0, 1000.0}) {
            double t = angle/scale;
            State state = evolve(rotor, t);
            std::string where = describe(body, t);
            assertSmall(orthonormality(state.attitude), 1e-13, "orthonormality of A", where, __LINE__);
            assertSmall(std::fabs(det(state.attitude) - 1.0), 1e-13, "det A", where, __LINE__);
            assertSmall(std::fabs(kineticEnergy(body.moments, state.omega) - energy), 1e-13*energy, "energy", where, __LINE__);
            assertSmall(std::fabs(vectorNorm(bodyAngularMomentum(body.moments, state.omega)) - l), 1e-13*l, "|L|", where, __LINE__);
            assertSmall(maxDifference(labAngularMomentum(body.moments, state), lab), 1e-13*(10 + std::fabs(angle))*l,
                        "L_lab", where, __LINE__);
        }
    }
}

/** Agreement with the RK4 reference integration at three times up to |omega| t = 3, to 1e-9. */
void testAgainstIntegration() {
    for (const Body& body : allBodies(6)) {
        double scale = omegaScale(body);
        std::vector<double> times = {clampTime(0.4/scale, body), clampTime(1.3/scale, body), clampTime(3.0/scale, body)};
        std::vector<State> reference = integrate(body, times);
        for (FreeRotor::Representation representation : {FreeRotor::Automatic, FreeRotor::EllipticIntegral}) {
            FreeRotor rotor = makeRotor(body, representation);
            for (int i = 0; i < (int) times.size(); i++) {
                State state = evolve(rotor, times[i]);
                std::string where = describe(body, times[i]) + " (representation " + std::to_string(rotor.getRepresentation()) + ")";
                assertSmall(maxDifference(reference[i].omega, state.omega)/scale, 1e-9, "omega vs RK4", where, __LINE__);
                assertSmall(maxDifference(reference[i].attitude, state.attitude), 1e-9, "A vs RK4", where, __LINE__);
            }
        }
    }
}

/**
 * Rotation about a principal axis is steady: omega constant, A(t) = exp(W(-omega t)) A(0). This covers
 * the unstable middle axis (m = 1 exactly) and the singular T1' of vZS eq. (3.13) (L along axis 3).
 */
void testSteadyRotation() {
    for (const Vector3& moments : ASYMMETRIC_MOMENTS)
        for (int axis = 0; axis < 3; axis++)
            for (double size : {-2.3, 1e-3, 4.0}) {
                Vector3 omega = {0, 0, 0};
                omega[axis] = size;
                Body body = {moments, omega, RigidBodyTestSupport::randomRotation(normal), "steady rotation about axis " + std::to_string(axis)};
                FreeRotor rotor = makeRotor(body);
                for (double angle : {0.5, -2.0, 20.0}) {
                    double t = angle/std::fabs(size);
                    State state = evolve(rotor, t);
                    std::string where = describe(body, t);
                    assertSmall(maxDifference(omega, state.omega)/std::fabs(size), 1e-15, "steady omega", where, __LINE__);
                    Matrix3 expected = product(rodrigues({-omega[0]*t, -omega[1]*t, -omega[2]*t}), body.attitude);
                    assertSmall(maxDifference(expected, state.attitude), 1e-13*(1 + std::fabs(angle)), "steady A", where, __LINE__);
                }
            }
    // A spherical top and a linear rotor always rotate steadily.
    for (const Body& body : randomBodies(FreeRotor::Spherical, 10)) {
        FreeRotor rotor = makeRotor(body);
        double t = 7.0/omegaScale(body);
        State state = evolve(rotor, t);
        Matrix3 expected = product(rodrigues({-body.omega[0]*t, -body.omega[1]*t, -body.omega[2]*t}), body.attitude);
        assertSmall(maxDifference(body.omega, state.omega)/omegaScale(body), 1e-15, "spherical omega", describe(body, t), __LINE__);
        assertSmall(maxDifference(expected, state.attitude), 1e-12, "spherical A", describe(body, t), __LINE__);
    }
    for (const Body& body : randomBodies(FreeRotor::Linear, 10)) {
        FreeRotor rotor = makeRotor(body);
        Vector3 omega = effectiveOmega(body);
        double t = 7.0/omegaScale(body);
        State state = evolve(rotor, t);
        Matrix3 expected = product(rodrigues({-omega[0]*t, -omega[1]*t, -omega[2]*t}), body.attitude);
        assertSmall(maxDifference(omega, state.omega)/omegaScale(body), 1e-15, "linear omega", describe(body, t), __LINE__);
        assertSmall(maxDifference(expected, state.attitude), 1e-12, "linear A", describe(body, t), __LINE__);
    }
}

/** The flow property: evolve(t1 + t2) equals evolve(t2) of a rotor built from the state at t1, to 1e-9. */
void testFlowProperty() {
    for (const Body& body : allBodies(30)) {
        double scale = omegaScale(body);
        FreeRotor rotor = makeRotor(body);
        for (int trial = 0; trial < 4; trial++) {
            double t1 = uniform(-10, 10)/scale, t2 = uniform(-10, 10)/scale;
            if (trial == 0)
                t2 = -t1;  // back to the start exactly
            t2 = clampTime(t2, body);  // the restart state's rounding is amplified over t2 only
            State middle = evolve(rotor, t1);
            State direct = evolve(rotor, t1 + t2);
            FreeRotor restarted = makeRotor({body.moments, middle.omega, middle.attitude, body.name + " restarted at t1 = " + str(t1)});
            State composed = evolve(restarted, t2);
            std::string where = describe(body, t1) + ", then t2 = " + str(t2);
            assertSmall(maxDifference(direct.omega, composed.omega)/scale, 1e-9, "flow property, omega", where, __LINE__);
            assertSmall(maxDifference(direct.attitude, composed.attitude), 1e-9, "flow property, A", where, __LINE__);
        }
    }
}

/** Time reversal: from the state at t with omega negated, evolving by t returns to (A(0), -omega(0)), to 1e-10. */
void testTimeReversal() {
    for (const Body& body : allBodies(30)) {
        double scale = omegaScale(body);
        FreeRotor rotor = makeRotor(body);
        Vector3 omega0 = effectiveOmega(body);
        for (double angle : {0.01, 1.0, uniform(0, 20)}) {
            double t = clampTime(angle/scale, body);
            State forward = evolve(rotor, t);
            Vector3 reversed = {-forward.omega[0], -forward.omega[1], -forward.omega[2]};
            State back = evolve(makeRotor({body.moments, reversed, forward.attitude, body.name + " reversed at t = " + str(t)}), t);
            std::string where = describe(body, t);
            assertSmall(maxDifference(back.attitude, body.attitude), 1e-10, "time reversal, A", where, __LINE__);
            assertSmall(maxDifference(back.omega, {-omega0[0], -omega0[1], -omega0[2]})/scale, 1e-10,
                        "time reversal, omega", where, __LINE__);
        }
    }
}

/**
 * The two exact representations of the asymmetric top's precession angle agree for m in [0.3, 0.99]:
 * to 1e-11 in omega (relative) and A, for |omega| t up to 20.
 */
void testRepresentationsAgree() {
    int counts[7] = {0};  // bins of width 0.1 from 0.3; the last is [0.9, 0.99]
    int found = 0;
    for (int attempt = 0; attempt < 200000 && found < 70; attempt++) {
        Body body = randomBodies(FreeRotor::Asymmetric, 1)[0];
        FreeRotor theta = makeRotor(body, FreeRotor::ThetaSeries);
        double m = theta.getParameter();
        if (!(m >= 0.3 && m <= 0.99))
            continue;
        int bin = std::min(6, (int) ((m - 0.3)/0.1));
        if (counts[bin] >= 10)
            continue;
        counts[bin]++;
        found++;
        FreeRotor integral = makeRotor(body, FreeRotor::EllipticIntegral);
        ASSERT_EQUAL(FreeRotor::ThetaSeries, theta.getRepresentation());
        ASSERT_EQUAL(FreeRotor::EllipticIntegral, integral.getRepresentation());
        ASSERT_EQUAL_TOL(m, integral.getParameter(), 0.0);
        double scale = omegaScale(body);
        for (double angle : {0.0, 0.2, -1.5, 4.0, 11.0, 20.0}) {
            double t = angle/scale;
            State a = evolve(theta, t), b = evolve(integral, t);
            std::string where = describe(body, t) + " (m = " + str(m) + ")";
            assertSmall(maxDifference(a.omega, b.omega)/scale, 1e-11, "theta series vs elliptic integral, omega", where, __LINE__);
            assertSmall(maxDifference(a.attitude, b.attitude), 1e-11, "theta series vs elliptic integral, A", where, __LINE__);
        }
    }
    ASSERT_EQUAL(70, found);
}

/**
 * Moments equal to 1e-12 relative (an asymmetric top with m ~ 1e-12) agree with the exact symmetric
 * or spherical top to 1e-10 for |omega| t up to 2: the physical difference is ~1e-12 |omega t|.
 */
void testNearlySymmetric() {
    struct Pair { Vector3 nearly, exact; };
    std::vector<Pair> pairs = {{{10, 10*(1 + 1e-12), 26}, {10, 10, 26}},
                               {{10*(1 + 1e-12), 10, 26}, {10, 10, 26}},
                               {{10, 26*(1 - 1e-12), 26}, {10, 26, 26}},
                               {{26, 10*(1 + 1e-12), 10}, {26, 10, 10}},
                               {{26*(1 + 1e-12), 10, 26}, {26, 10, 26}},
                               {{10, 10*(1 + 1e-12), 10*(1 + 2e-12)}, {10, 10, 10}},
                               {{3.3*(1 - 1e-12), 3.3, 3.3*(1 + 1e-12)}, {3.3, 3.3, 3.3}}};
    for (const Pair& pair : pairs)
        for (int trial = 0; trial < 10; trial++) {
            Body body = {pair.nearly, randomOmega(), RigidBodyTestSupport::randomRotation(normal), "nearly symmetric"};
            FreeRotor nearly = makeRotor(body);
            FreeRotor exact = makeRotor({pair.exact, body.omega, body.attitude, "exactly symmetric"});
            ASSERT(exact.getKind() == FreeRotor::Symmetric || exact.getKind() == FreeRotor::Spherical);
            double scale = omegaScale(body);
            for (double angle : {0.1, 1.0, -2.0}) {
                double t = angle/scale;
                State a = evolve(nearly, t), b = evolve(exact, t);
                std::string where = describe(body, t) + " (" + FreeRotor::kindName(nearly.getKind()) + ", m = " +
                                    str(nearly.getParameter()) + ")";
                assertSmall(maxDifference(a.omega, b.omega)/scale, 1e-10, "nearly vs exactly symmetric, omega", where, __LINE__);
                assertSmall(maxDifference(a.attitude, b.attitude), 1e-10, "nearly vs exactly symmetric, A", where, __LINE__);
            }
        }
}

/**
 * Euler's equations are homogeneous: scaling omega by s and time by 1/s, or all moments by mu, maps
 * solutions to solutions. Checked for s, mu from 1e-8 to 1e8, to 1e-12.
 */
void testScaling() {
    // s = 2^-1030 makes omega subnormal and s = 1e307 puts it within a factor 4 of the largest double,
    // the two ends of the internal scaling of omega by a power of two. A subnormal omega keeps fewer
    // bits: it is compared with the rotor of the omega it rounds to (exact, since s is a power of two),
    // and at a smaller rotation angle, since t / s must stay finite.
    const double subnormal = std::ldexp(1.0, -1030);
    for (const Body& body : allBodies(3)) {
        for (double s : {1e-8, 1e8, subnormal, 1e307})
            for (double mu : {1e-6, 1.0, 1e6}) {
                if (mu*s > 1e300)
                    continue;  // the angular momentum itself would overflow
                Vector3 omega = {s*body.omega[0], s*body.omega[1], s*body.omega[2]};
                Body unscaled = body;
                if (s == subnormal)
                    unscaled.omega = {omega[0]/s, omega[1]/s, omega[2]/s};
                double t = (s == subnormal ? 1e-3 : 2.7)/omegaScale(body);
                State reference = evolve(makeRotor(unscaled), t);
                Vector3 moments = {mu*body.moments[0], mu*body.moments[1], mu*body.moments[2]};
                State state = evolve(makeRotor({moments, omega, body.attitude, body.name + " scaled"}), t/s);
                std::string where = describe(body, t) + " scaled by s = " + str(s) + ", mu = " + str(mu);
                Vector3 rescaled = {state.omega[0]/s, state.omega[1]/s, state.omega[2]/s};
                assertSmall(maxDifference(reference.omega, rescaled)/omegaScale(body), 1e-12, "scaled omega", where, __LINE__);
                assertSmall(maxDifference(reference.attitude, state.attitude), 1e-12, "scaled A", where, __LINE__);
            }
    }
}

/**
 * Exactly on the separatrix the motion approaches the unstable middle axis forever; long times must
 * stay finite, orthonormal and conservative (u = wp t beyond ~355 makes sech(u)^2 underflow).
 */
void testSeparatrixLongTimes() {
    Body body = {{1, 5, 9}, {3, 0.5, 1}, RigidBodyTestSupport::randomRotation(normal), "exact separatrix"};
    FreeRotor rotor = makeRotor(body);
    ASSERT_EQUAL_TOL(1.0, rotor.getParameter(), 0.0);
    double energy = kineticEnergy(body.moments, body.omega);
    Vector3 lab = labAngularMomentum(body.moments, {body.omega, body.attitude});
    double l = vectorNorm(lab);
    for (double t : {10.0, 100.0, 300.0, 1000.0, 1e4}) {
        State state = evolve(rotor, t);
        std::string where = describe(body, t);
        assertSmall(orthonormality(state.attitude), 1e-13, "orthonormality of A", where, __LINE__);
        assertSmall(std::fabs(kineticEnergy(body.moments, state.omega) - energy), 1e-13*energy, "energy", where, __LINE__);
        assertSmall(maxDifference(labAngularMomentum(body.moments, state), lab), 1e-13*(10 + 4*t)*l, "L_lab", where, __LINE__);
    }
}

/**
 * Off-axis components so small that their squares underflow (1e-200, 1e-300 of the axial one) are
 * valid input: the motion is steady rotation about the principal axis to far below rounding, for
 * |omega| t up to 20 even about the unstable middle axis (growth exp(lambda t) < 1e200).
 */
void testTinyOffAxisComponents() {
    for (const Vector3& moments : ASYMMETRIC_MOMENTS)
        for (int axis = 0; axis < 3; axis++)
            for (double small : {1e-200, 1e-300}) {
                Vector3 omega = {small, -small, 0.5*small};
                omega[axis] = 1.7;
                Body body = {moments, omega, RigidBodyTestSupport::randomRotation(normal), "principal axis " + std::to_string(axis) + " with off-axis " + str(small)};
                FreeRotor rotor = makeRotor(body);
                for (double angle : {0.0, 0.5, -2.0, 20.0}) {
                    double t = angle/1.7;
                    State state = evolve(rotor, t);
                    std::string where = describe(body, t);
                    Matrix3 expected = product(rodrigues({-omega[0]*t, -omega[1]*t, -omega[2]*t}), body.attitude);
                    assertSmall(maxDifference(omega, state.omega)/1.7, 1e-15, "steady omega", where, __LINE__);
                    assertSmall(maxDifference(expected, state.attitude), 1e-13*(1 + std::fabs(angle)), "steady A", where, __LINE__);
                }
            }
}

/** Bad input is rejected with std::invalid_argument naming the problem. */
/**
 * FreeRotor::advance (construct and evolve once, with the theta series at the start and at t summed
 * together) gives what the constructor and evolve() give, for every kind and the delicate bodies, at
 * times up to many periods and of both signs; and the independent integration agrees with it.
 */
void testAdvance() {
    std::vector<Body> bodies = allBodies(8);
    for (const Body& body : delicateBodies())
        bodies.push_back(body);
    for (const Body& body : bodies) {
        double scale = omegaScale(body);
        FreeRotor rotor = makeRotor(body);
        for (double t : {0.0, clampTime(0.01/scale, body), clampTime(-0.7/scale, body), clampTime(25.0/scale, body)}) {
            State expected = evolve(rotor, t);
            State state = {body.omega, body.attitude};
            FreeRotor::advance(body.moments, state.omega, state.attitude, t);
            std::string where = describe(body, t);
            // The fused sums add the same terms in the same order: agreement to a few ulps of the phase.
            double tolerance = 1e-14*(1.0 + std::fabs(t)*scale);
            assertSmall(maxDifference(expected.omega, state.omega)/scale, tolerance, "advance omega vs evolve", where, __LINE__);
            assertSmall(maxDifference(expected.attitude, state.attitude), tolerance, "advance A vs evolve", where, __LINE__);
        }
    }
    Body body = randomBodies(FreeRotor::Asymmetric, 1)[0];
    double scale = omegaScale(body);
    std::vector<double> times = {clampTime(0.9/scale, body)};
    State reference = integrate(body, times)[0];
    State state = {body.omega, body.attitude};
    FreeRotor::advance(body.moments, state.omega, state.attitude, times[0]);
    assertSmall(maxDifference(reference.omega, state.omega)/scale, 1e-9, "advance omega vs RK4", describe(body, times[0]), __LINE__);
    assertSmall(maxDifference(reference.attitude, state.attitude), 1e-9, "advance A vs RK4", describe(body, times[0]), __LINE__);
    const double nan = std::numeric_limits<double>::quiet_NaN();
    Vector3 omega = {0.3, -1.0, 2.0};
    Matrix3 attitude = RigidBodyTestSupport::randomRotation(normal);
    assertThrowsInvalidArgument([&]() { FreeRotor::advance({1, 2, 3}, omega, attitude, nan); }, "advance(NaN)", __LINE__);
    assertThrowsInvalidArgument([&]() { FreeRotor::advance({-1, 2, 3}, omega, attitude, 1.0); }, "advance, negative moment", __LINE__);
}

void testInvalidInput() {
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    const Matrix3 identity = {{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
    const Vector3 omega = {0.3, -1.0, 2.0};
    auto build = [&](Vector3 moments, Vector3 w, Matrix3 attitude) {
        return [=]() { FreeRotor rotor(moments, w, attitude); };
    };
    assertThrowsInvalidArgument(build({-1, 2, 3}, omega, identity), "negative moment", __LINE__);
    assertThrowsInvalidArgument(build({1, 2, -1e-300}, omega, identity), "negative moment", __LINE__);
    assertThrowsInvalidArgument(build({nan, 2, 3}, omega, identity), "NaN moment", __LINE__);
    assertThrowsInvalidArgument(build({1, inf, 3}, omega, identity), "infinite moment", __LINE__);
    assertThrowsInvalidArgument(build({0, 0, 3}, omega, identity), "two zero moments", __LINE__);
    assertThrowsInvalidArgument(build({0, 0, 0}, omega, identity), "three zero moments", __LINE__);
    assertThrowsInvalidArgument(build({0, 1, 2}, omega, identity), "zero moment with unequal others", __LINE__);
    assertThrowsInvalidArgument(build({1, 2, 3}, {nan, 0, 0}, identity), "NaN omega", __LINE__);
    assertThrowsInvalidArgument(build({1, 2, 3}, {0, -inf, 0}, identity), "infinite omega", __LINE__);
    assertThrowsInvalidArgument(build({2, 2, 2}, {0, 0, nan}, identity), "NaN omega (spherical)", __LINE__);
    Matrix3 scaled = RigidBodyTestSupport::randomRotation(normal);
    for (auto& row : scaled)
        for (double& x : row)
            x *= 1.001;
    assertThrowsInvalidArgument(build({1, 2, 3}, omega, scaled), "attitude scaled by 1.001", __LINE__);
    Matrix3 sheared = identity;
    sheared[0][1] = 1e-6;
    assertThrowsInvalidArgument(build({1, 2, 3}, omega, sheared), "sheared attitude", __LINE__);
    assertThrowsInvalidArgument(build({1, 2, 3}, omega, Matrix3{}), "zero attitude", __LINE__);
    Matrix3 reflection = {{{1, 0, 0}, {0, 1, 0}, {0, 0, -1}}};
    assertThrowsInvalidArgument(build({1, 2, 3}, omega, reflection), "reflection (det -1)", __LINE__);
    Matrix3 withNan = identity;
    withNan[2][1] = nan;
    assertThrowsInvalidArgument(build({1, 2, 3}, omega, withNan), "NaN in attitude", __LINE__);
    assertThrowsInvalidArgument([&]() { FreeRotor rotor({1, 2, 3}, omega, identity, (FreeRotor::Representation) 7); },
                                "unknown representation", __LINE__);
    // The theta series does not exist on the separatrix (m = 1); asking for it there is an error.
    assertThrowsInvalidArgument([&]() { FreeRotor rotor({1, 5, 9}, {3, 0.5, 1}, identity, FreeRotor::ThetaSeries); },
                                "theta series on the separatrix", __LINE__);
    FreeRotor rotor({1, 2, 3}, omega, identity);
    assertThrowsInvalidArgument([&]() { State s = evolve(rotor, nan); (void) s; }, "evolve(NaN)", __LINE__);
    // Rounding-level deviations from orthonormality, as produced by a caller's arithmetic, are accepted.
    Matrix3 nearly = RigidBodyTestSupport::randomRotation(normal);
    nearly[1][2] += 1e-14;
    FreeRotor accepted({1, 2, 3}, omega, nearly);
    (void) accepted;
}

/**
 * The one classification (rigidClassifyMoments, used by the rotor and the body topology): moments
 * equal to within 1e-13 of the largest are one kind and are made exactly equal; moments 1e-12 apart
 * stay an asymmetric top. A snapped rotor is exactly the rotor of its snapped moments, and (unless a
 * moment was taken as zero) follows the motion of the given moments (RK4 reference) to 1e-9.
 */
void testClassification() {
    struct Case { Vector3 moments; FreeRotor::Kind kind; };
    std::vector<Case> cases = {{{2, 2, 2}, FreeRotor::Spherical}, {{2, 2*(1 + 4e-14), 2*(1 - 4e-14)}, FreeRotor::Spherical},
                               {{2, 2, 3}, FreeRotor::Symmetric}, {{3, 2, 2*(1 + 5e-14)}, FreeRotor::Symmetric},
                               {{2*(1 - 5e-14), 3, 2}, FreeRotor::Symmetric}, {{0, 2, 2}, FreeRotor::Linear},
                               {{2, 1e-14, 2*(1 + 5e-14)}, FreeRotor::Linear}, {{1, 1 + 1e-12, 3}, FreeRotor::Asymmetric},
                               {{1e-12, 1, 1}, FreeRotor::Symmetric}, {{10, 10*(1 + 1e-12), 26}, FreeRotor::Asymmetric}};
    for (const Case& c : cases) {
        Body body = {c.moments, randomOmega(), RigidBodyTestSupport::randomRotation(normal), "classification case"};
        FreeRotor rotor = makeRotor(body);
        std::string where = describe(body, 0.0);
        if (rotor.getKind() != c.kind)
            throwException(__FILE__, __LINE__, "kind " + std::string(FreeRotor::kindName(rotor.getKind())) + " for " + where);
        const Vector3& used = rotor.getMoments();
        const double largest = std::max({c.moments[0], c.moments[1], c.moments[2]});
        for (int k = 0; k < 3; k++)
            assertSmall(std::fabs(used[k] - c.moments[k]), 1e-13*largest, "snapped moment", where, __LINE__);
        int equal = (used[0] == used[1]) + (used[1] == used[2]) + (used[0] == used[2]);
        int expectedEqual = (c.kind == FreeRotor::Spherical ? 3 : c.kind == FreeRotor::Asymmetric ? 0 : 1);
        ASSERT_EQUAL(expectedEqual, equal);
        // The snapped rotor is the rotor of the snapped moments, to the last bit.
        FreeRotor snapped = makeRotor({used, body.omega, body.attitude, "snapped"});
        double scale = omegaScale(body);
        std::vector<double> times = {0.7/scale, 2.9/scale};
        std::vector<State> reference = integrate(body, times);
        for (size_t n = 0; n < times.size(); n++) {
            State a = evolve(rotor, times[n]), b = evolve(snapped, times[n]);
            assertSmall(maxDifference(a.omega, b.omega), 0.0, "snapped rotor vs rotor of the snapped moments", where, __LINE__);
            assertSmall(maxDifference(a.attitude, b.attitude), 0.0, "snapped rotor vs rotor of the snapped moments", where, __LINE__);
            if (std::min({c.moments[0], c.moments[1], c.moments[2]}) < 1e-3*largest)
                continue;  // a tiny moment: too stiff for the RK4 reference (and one taken as zero drops its spin)
            assertSmall(maxDifference(reference[n].omega, a.omega)/scale, 1e-9, "snapped rotor vs RK4", where, __LINE__);
            assertSmall(maxDifference(reference[n].attitude, a.attitude), 1e-9, "snapped rotor vs RK4", where, __LINE__);
        }
    }
    // What the topology sees: the moments of a symmetric or spherical shape whose coordinates were
    // differences of positions 2 to 6 nm from the origin (RigidBody::setShape's arithmetic: principal
    // axes, then the diagonal of the rotated coordinates' inertia tensor) stay symmetric or spherical.
    const double r = 0.1/std::sqrt(3.0);
    std::vector<Vector3> tetrahedron = {{r, r, r}, {r, -r, -r}, {-r, r, -r}, {-r, -r, r}};
    std::vector<Vector3> pyramid = {{0, 0, 0.04}};
    for (int k = 0; k < 3; k++)
        pyramid.push_back({0.094*std::cos(2*M_PI*k/3), 0.094*std::sin(2*M_PI*k/3), 0.0});
    double worst = 0.0;
    for (int trial = 0; trial < 200; trial++) {
        bool spherical = (trial%2 == 0);
        const std::vector<Vector3>& shape = (spherical ? tetrahedron : pyramid);
        std::vector<double> masses = (spherical ? std::vector<double>{1, 1, 1, 1} : std::vector<double>{14, 1, 1, 1});
        Matrix3 rotation = RigidBodyTestSupport::randomRotation(normal);
        Vector3 centre = {uniform(2, 6), uniform(2, 6), uniform(2, 6)};
        std::vector<Vector3> positions;
        Vector3 mean = {0, 0, 0};
        double total = 0;
        for (size_t i = 0; i < shape.size(); i++) {
            Vector3 p = multiply(rotation, shape[i]);
            positions.push_back({p[0] + centre[0], p[1] + centre[1], p[2] + centre[2]});
            for (int k = 0; k < 3; k++)
                mean[k] += masses[i]*positions.back()[k];
            total += masses[i];
        }
        std::vector<Vector3> centred;
        for (const Vector3& p : positions)
            centred.push_back({p[0] - mean[0]/total, p[1] - mean[1]/total, p[2] - mean[2]/total});
        Vector3 moments;
        Matrix3 axes;
        principalAxes(centred, masses, moments, axes);
        for (int k = 0; k < 3; k++) {
            moments[k] = 0.0;
            for (size_t i = 0; i < centred.size(); i++) {
                Vector3 b = multiplyTransposed(axes, centred[i]);
                moments[k] += masses[i]*(dot(b, b) - b[k]*b[k]);
            }
        }
        const double largest = std::max({moments[0], moments[1], moments[2]});
        worst = std::max(worst, (spherical ? std::max({moments[0], moments[1], moments[2]}) - std::min({moments[0], moments[1], moments[2]}) :
                                 std::min({std::fabs(moments[0] - moments[1]), std::fabs(moments[1] - moments[2]), std::fabs(moments[0] - moments[2])}))/largest);
        RigidShape classified = FreeRotor::classify(moments);
        ASSERT_EQUAL(spherical ? RigidKindSpherical : RigidKindSymmetric, classified.kind);
    }
    std::cout << "largest relative spread of equal moments from coordinates 2-6 nm from the origin: " << worst << std::endl;
    // Errors: a point (all moments zero) and the impossible cases are no rotor.
    assertThrowsInvalidArgument([]() { FreeRotor::classify({1e-20, 1e-20, 1.0}); }, "two zero moments", __LINE__);
    assertThrowsInvalidArgument([]() { FreeRotor::classify({0, 1, 1 + 1e-12}); }, "zero moment, unequal others", __LINE__);
    RigidShape point;
    ASSERT_EQUAL(RigidStatusOk, rigidClassifyMoments(Vector3{0, 0, 0}.data(), &point));
    ASSERT_EQUAL(RigidKindPoint, point.kind);
    // A point does not turn: rigidRotorAdvance keeps its attitude and zeroes omega.
    Matrix3 original = RigidBodyTestSupport::randomRotation(normal);
    double attitude[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            attitude[i][j] = original[i][j];
    Vector3 omega = {0.3, -0.2, 0.1};
    ASSERT_EQUAL(RigidStatusOk, rigidRotorAdvance(&point, omega.data(), attitude, 1.5));
    for (int i = 0; i < 3; i++) {
        ASSERT_EQUAL_TOL(0.0, omega[i], 0.0);
        for (int j = 0; j < 3; j++)
            ASSERT_EQUAL_TOL(original[i][j], attitude[i][j], 0.0);
    }
}

/**
 * The integrator's entry point rigidRotorAdvance() (no checks) gives what FreeRotor::advance gives,
 * bit for bit, for every kind and the delicate bodies.
 */
void testCoreAdvance() {
    for (const Body& body : allBodies(5)) {
        RigidShape shape = FreeRotor::classify(body.moments);
        double scale = omegaScale(body);
        for (double t : {0.0, 0.02/scale, -1.1/scale, 30.0/scale}) {
            State expected = {body.omega, body.attitude};
            FreeRotor::advance(body.moments, expected.omega, expected.attitude, t);
            Vector3 omega = body.omega;
            double attitude[3][3];
            for (int i = 0; i < 3; i++)
                for (int j = 0; j < 3; j++)
                    attitude[i][j] = body.attitude[i][j];
            ASSERT_EQUAL(RigidStatusOk, rigidRotorAdvance(&shape, omega.data(), attitude, t));
            Matrix3 a;
            for (int i = 0; i < 3; i++)
                for (int j = 0; j < 3; j++)
                    a[i][j] = attitude[i][j];
            assertSmall(maxDifference(expected.omega, omega), 0.0, "rigidRotorAdvance omega", describe(body, t), __LINE__);
            assertSmall(maxDifference(expected.attitude, a), 0.0, "rigidRotorAdvance A", describe(body, t), __LINE__);
        }
    }
}

/** Whether two arrays of doubles are the same bits (so -0.0 differs from 0.0, and NaN is caught). */
static bool sameBits(const double* a, const double* b, int n) {
    return std::memcmp(a, b, n*sizeof(double)) == 0;
}

/**
 * The host platforms' drift turns bodies RigidLanes at a time (advanceFreeRotors, the library's
 * vectorized rigidRotorAdvanceLanes): each body must come out as rigidRotorAdvance() gives it, bit
 * for bit, for every kind and delicate body, whichever bodies share the lanes and however many
 * there are. The bodies include asymmetric tops whose theta series need from 2 to 8 terms side by
 * side and tops on both sides of the automatic choice's limit m = 0.9999 (in lanes below it, the
 * scalar elliptic integral above it). The inline core function, as this test compiles it, is checked
 * the same way.
 */
void testRotorsInLanes() {
    std::vector<Body> bodies = allBodies(6);
    std::vector<Body> spread = randomBodies(FreeRotor::Asymmetric, 40);
    bodies.insert(bodies.end(), spread.begin(), spread.end());
    int belowLimit = 0, aboveLimit = 0, fewestTerms = 100, mostTerms = 0;
    for (double offset = 1e-7; offset < 1e-2; offset *= 1.6)
        for (double sign : {1.0, -1.0}) {
            Vector3 moments = {1.3, 2.9, 4.1};
            bodies.push_back({moments, nearSeparatrixOmega(moments, {0.7, -1.1, 0.9}, sign*offset),
                              RigidBodyTestSupport::randomRotation(normal), "near the automatic limit, offset " + str(sign*offset)});
        }
    for (const Body& body : bodies) {
        FreeRotor rotor = makeRotor(body);
        const RigidRotor& core = rotor.getCore();
        if (core.kind != RigidKindAsymmetric || core.steady)
            continue;
        belowLimit += (core.m <= rigidAutomaticThetaSeriesLimit() && core.m > 0.999);
        aboveLimit += (core.m > rigidAutomaticThetaSeriesLimit());
        if (core.representation == RigidRepresentationThetaSeries) {
            fewestTerms = std::min(fewestTerms, core.thetaTerms);
            mostTerms = std::max(mostTerms, core.thetaTerms);
        }
    }
    ASSERT(belowLimit >= 2 && aboveLimit >= 2);
    ASSERT(fewestTerms <= 3 && mostTerms == 8);
    const int numBodies = bodies.size();
    for (int count = 1; count <= RigidLanes; count++)
        for (int first = 0; first < numBodies; first++) {
            const double t = std::vector<double>{0.0, 0.02, -1.1, 30.0}[(first + count)%4];
            RigidShape shapes[RigidLanes];
            double omega[RigidLanes][3], attitude[RigidLanes][3][3], omegaInline[RigidLanes][3], attitudeInline[RigidLanes][3][3];
            double expectedOmega[RigidLanes][3], expectedAttitude[RigidLanes][3][3];
            std::string names;
            for (int lane = 0; lane < count; lane++) {
                // neighbours, and bodies far apart in the list, share the lanes
                const Body& body = bodies[(first + lane*(1 + first%7))%numBodies];
                names += body.name + "; ";
                shapes[lane] = FreeRotor::classify(body.moments);
                for (int i = 0; i < 3; i++) {
                    omega[lane][i] = omegaInline[lane][i] = expectedOmega[lane][i] = body.omega[i];
                    for (int j = 0; j < 3; j++)
                        attitude[lane][i][j] = attitudeInline[lane][i][j] = expectedAttitude[lane][i][j] = body.attitude[i][j];
                }
                ASSERT_EQUAL(RigidStatusOk, rigidRotorAdvance(&shapes[lane], expectedOmega[lane], expectedAttitude[lane], t));
            }
            advanceFreeRotors(count, shapes, omega, attitude, t);
            ASSERT_EQUAL(RigidStatusOk, rigidRotorAdvanceLanes(count, shapes, omegaInline, attitudeInline, t));
            for (int lane = 0; lane < count; lane++)
                if (!sameBits(expectedOmega[lane], omega[lane], 3) || !sameBits(&expectedAttitude[lane][0][0], &attitude[lane][0][0], 9) ||
                        !sameBits(expectedOmega[lane], omegaInline[lane], 3) ||
                        !sameBits(&expectedAttitude[lane][0][0], &attitudeInline[lane][0][0], 9))
                    throw std::runtime_error("lane " + std::to_string(lane) + " of " + std::to_string(count) +
                                             " differs from rigidRotorAdvance at t = " + str(t) + "; lanes: " + names);
        }
}

/**
 * The host drift's correction of the attitudes after the exact rotation (reorthonormalizeAttitudes,
 * compiled as advanceFreeRotors is) must be rigidReorthonormalize() bit for bit, for 1 to RigidLanes
 * attitudes at once, and must do its job: attitudes off a rotation by 1e-12 to 1e-6 come out with
 * |A A^T - 1| of the order of the square of that, or rounding.
 */
void testReorthonormalizeAttitudes() {
    for (int trial = 0; trial < 400; trial++) {
        const int count = 1 + trial%RigidLanes;
        double attitude[RigidLanes][3][3], expected[RigidLanes][3][3];
        for (int lane = 0; lane < count; lane++) {
            const Matrix3 rotation = RigidBodyTestSupport::randomRotation(normal);
            const double size = std::pow(10.0, -12.0 + 6.0*(trial%13)/12.0);
            for (int i = 0; i < 3; i++)
                for (int j = 0; j < 3; j++)
                    attitude[lane][i][j] = expected[lane][i][j] = rotation[i][j] + size*normal();
            rigidReorthonormalize(expected[lane]);
        }
        reorthonormalizeAttitudes(count, attitude);
        for (int lane = 0; lane < count; lane++) {
            if (!sameBits(&expected[lane][0][0], &attitude[lane][0][0], 9))
                throw std::runtime_error("reorthonormalizeAttitudes differs from rigidReorthonormalize in lane " + std::to_string(lane));
            double worst = 0.0;
            for (int i = 0; i < 3; i++)
                for (int j = 0; j < 3; j++) {
                    const double dot = attitude[lane][i][0]*attitude[lane][j][0] + attitude[lane][i][1]*attitude[lane][j][1] +
                                       attitude[lane][i][2]*attitude[lane][j][2];
                    worst = std::max(worst, std::fabs(dot - (i == j ? 1.0 : 0.0)));
                }
            const double size = std::pow(10.0, -12.0 + 6.0*(trial%13)/12.0);
            ASSERT(worst < 1e-15 + 100.0*size*size);
        }
    }
}

int main() {
    try {
        testPaperExample();
        testAccessors();
        testInitialState();
        testAgainstIntegration();
        testFlowProperty();
        testTimeReversal();
        testSteadyRotation();
        testRepresentationsAgree();
        testNearlySymmetric();
        testScaling();
        testConservation();
        testSeparatrixLongTimes();
        testTinyOffAxisComponents();
        testAdvance();
        testInvalidInput();
        testClassification();
        testCoreAdvance();
        testRotorsInLanes();
        testReorthonormalizeAttitudes();
    }
    catch (const std::exception& e) {
        std::cout << "exception: " << e.what() << std::endl;
        return 1;
    }
    std::cout << "Done" << std::endl;
    return 0;
}
