#ifndef OPENMMRIGID_NUMERICS_FREEROTOR_H_
#define OPENMMRIGID_NUMERICS_FREEROTOR_H_

/*
 * The exact motion of a free rigid rotor (R. van Zon and J. Schofield, J. Comput. Phys. 225 (2007)
 * 145-164), as a validating class for the API, the Python module and the tests. The numerics are
 * the core's (numerics/core/CoreRotor.h, compiled as C++ by numerics/RigidCore.h): its file comment
 * states the kinds, the two representations of the asymmetric top and the accuracy, and
 * docs/free-rotor-notes.md restates the algorithm. This class checks its input, throws
 * std::invalid_argument naming the problem, and otherwise only calls the core; an integrator's drift
 * calls the core's rigidRotorAdvance() directly, with the body's RigidShape.
 *
 * Kinds come from rigidClassifyMoments(), the one classification the body topology uses as well:
 * moments equal to within 1e-13 of the largest are made exactly equal (see its comment).
 */

#include "numerics/Matrix3.h"
#include "numerics/RigidCore.h"
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace OpenMMRigid {

/**
 * The exact torque-free motion of a rigid body. Its angular velocity and attitude at any time follow
 * in closed form from the initial state: Jacobi elliptic functions and either a theta series or an
 * elliptic integral of the third kind for an asymmetric top (R. van Zon and J. Schofield, J. Comput.
 * Phys. 225, 145 (2007)), elementary functions for linear, spherical and symmetric tops. This is the
 * rotational half of the free drift of the integrators, exposed for checks and diagnostics.
 *
 * All quantities may be in any consistent units (for example amu nm^2, 1/ps and ps).
 */
class FreeRotor {
public:
    enum Kind { Linear = RigidKindLinear, Spherical = RigidKindSpherical, Symmetric = RigidKindSymmetric,
                Asymmetric = RigidKindAsymmetric };
    enum Representation { Automatic = RigidRepresentationAutomatic, ThetaSeries = RigidRepresentationThetaSeries,
                          EllipticIntegral = RigidRepresentationEllipticIntegral };
    /** Automatic uses the theta series up to this elliptic parameter m, the elliptic integral above (rigidAutomaticThetaSeriesLimit()). */
    static constexpr double automaticThetaSeriesLimit = 0.9999;

    /**
     * Create the rotor from its initial state.
     *
     * @param moments         the three principal moments of inertia (mass x length^2), non-negative, in
     *                        any order. One may be zero if the other two are equal: a linear rotor, whose
     *                        zero moment marks its axis.
     * @param omega           the angular velocity in the body (principal-axis) frame at t = 0 (1/time)
     * @param attitude        the lab-to-body rotation matrix A(0), orthonormal with determinant +1, so
     *                        that A v_lab gives body components
     * @param representation  how an asymmetric top evaluates its rotation angle: Automatic picks the
     *                        cheaper of the two exact forms, ThetaSeries and EllipticIntegral force one
     *                        of them, for diagnostics (numerics/core/CoreRotor.h). Ignored for the other
     *                        kinds.
     * @param checkInput      whether to check that the input is finite and the attitude a rotation. Only
     *                        a caller that guarantees both (the integrator, whose attitudes are kept
     *                        orthonormal and whose momenta are checked every step) may skip it.
     * @throws std::invalid_argument naming the problem, for non-finite or inconsistent input (a negative
     *         moment, moments that are no rotor, an attitude that is not a rotation), or a forced
     *         representation that cannot describe this motion
     */
    FreeRotor(const Vector3& moments, const Vector3& omega, const Matrix3& attitude = identityMatrix(),
              Representation representation = Automatic, bool checkInput = true);

    /**
     * Get the state at time t.
     *
     * @param t              the time from the initial state (any sign, in the time unit of omega)
     * @param[out] omega     the body-frame angular velocity omega(t) (1/time)
     * @param[out] attitude  the lab-to-body rotation matrix A(t)
     * @throws std::invalid_argument if t is not finite
     */
    void evolve(double t, Vector3& omega, Matrix3& attitude) const;

    /**
     * The state at time t of the rotor that starts from (omega, attitude), written over them: the same
     * result as FreeRotor(moments, omega, attitude).evolve(t, omega, attitude), for the caller that
     * evolves each initial state once (an integrator's drift). An asymmetric top evaluates its theta
     * series at the start and at t in one pass, which makes it cheaper than the two calls. It is
     * rigidRotorAdvance() with the checks of the constructor.
     *
     * @param checkInput  as for the constructor
     */
    static void advance(const Vector3& moments, Vector3& omega, Matrix3& attitude, double t, bool checkInput = true);

    /**
     * The kind and the moments the dynamics uses, by rigidClassifyMoments().
     *
     * @throws std::invalid_argument for moments that are no rotor (negative, two or three zero, or one
     *         zero with unequal others)
     */
    static RigidShape classify(const Vector3& moments);

    /** Get the kind of rotor, from its principal moments (rigidClassifyMoments()): Linear, Spherical, Symmetric or Asymmetric. */
    Kind getKind() const { return static_cast<Kind>(rotor.kind); }
    /** Get the name of a kind: "linear", "spherical", "symmetric" or "asymmetric". */
    static const char* kindName(Kind kind) {
        static const char* names[] = {"linear", "spherical", "symmetric", "asymmetric"};
        return names[kind];
    }
    /** Get the representation an asymmetric top uses (never Automatic); Automatic for the other kinds. */
    Representation getRepresentation() const { return static_cast<Representation>(rotor.representation); }
    /** Get the rotational kinetic energy 1/2 sum_k I_k omega_k^2 (mass x length^2 / time^2). */
    double getEnergy() const { return rotor.energy; }
    /** Get the angular momentum in the body frame at t = 0, I_k omega_k (mass x length^2 / time). */
    Vector3 getAngularMomentum() const {
        return {moments[0]*omega0[0], moments[1]*omega0[1], moments[2]*omega0[2]};
    }
    /**
     * Get the principal moments of inertia the motion uses: the given ones, with those the
     * classification found equal (or zero) made exactly so.
     */
    const Vector3& getMoments() const { return moments; }
    /**
     * Get the body-frame angular velocity at t = 0; for a linear rotor its component along the axis
     * is removed (it carries no motion).
     */
    const Vector3& getOmega() const { return omega0; }
    /** Get the lab-to-body rotation matrix at t = 0. */
    const Matrix3& getAttitude() const { return attitude0; }
    /** Get the elliptic parameter m (0 <= m <= 1) of an asymmetric top's motion (vZS eq. (3.40)); 0 for the other kinds. */
    double getParameter() const { return rotor.m; }
    /** The core's rotor, for a caller that evaluates it with rigidRotorEvolve() itself. */
    const RigidRotor& getCore() const { return rotor; }

private:
    static void validate(const Vector3& moments, const Vector3& omega, const Matrix3& attitude);
    /** Throws std::invalid_argument for a status of rigidRotorInitialize() other than RigidStatusOk. */
    static void requireInitialized(int status, int representation, double m);

    Vector3 moments, omega0;
    Matrix3 attitude0;
    RigidRotor rotor;
};

namespace detail {

/** x with every digit a double holds (17 significant), so that a message tells apart values that differ. */
inline std::string fullPrecision(double x) {
    std::ostringstream text;
    text.precision(17);
    text << x;
    return text.str();
}

inline void toArray(const Matrix3& a, double b[3][3]) {
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            b[i][j] = a[i][j];
}

inline void fromArray(double b[3][3], Matrix3& a) {
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            a[i][j] = b[i][j];
}

} // namespace detail

inline FreeRotor::FreeRotor(const Vector3& moments, const Vector3& omega, const Matrix3& attitude,
                            Representation requested, bool checkInput) {
    if (requested != Automatic && requested != ThetaSeries && requested != EllipticIntegral)
        throw std::invalid_argument("FreeRotor: unknown representation " + std::to_string((int) requested));
    if (checkInput)
        validate(moments, omega, attitude);
    const RigidShape shape = classify(moments);
    double a[3][3];
    detail::toArray(attitude, a);
    const int status = rigidRotorInitialize(&rotor, &shape, omega.data(), a, requested, 0, 0.0, nullptr);
    requireInitialized(status, requested, rotor.m);
    for (int k = 0; k < 3; k++) {
        this->moments[k] = rotor.moments[k];
        omega0[k] = rotor.omega0[k];
    }
    attitude0 = attitude;
}

inline void FreeRotor::advance(const Vector3& moments, Vector3& omega, Matrix3& attitude, double t, bool checkInput) {
    if (!std::isfinite(t))
        throw std::invalid_argument("FreeRotor::advance: the time is not finite");
    if (checkInput)
        validate(moments, omega, attitude);
    const RigidShape shape = classify(moments);
    double a[3][3];
    detail::toArray(attitude, a);
    requireInitialized(rigidRotorAdvance(&shape, omega.data(), a, t), Automatic, 0.0);
    detail::fromArray(a, attitude);
}

inline RigidShape FreeRotor::classify(const Vector3& moments) {
    RigidShape shape;
    switch (rigidClassifyMoments(moments.data(), &shape)) {
    case RigidStatusOk:
        break;
    case RigidStatusNegativeMoment:
        for (int k = 0; k < 3; k++)
            if (!(moments[k] >= 0.0))
                throw std::invalid_argument("FreeRotor: moment of inertia " + std::to_string(k) + " is " +
                        detail::fullPrecision(moments[k]) + "; moments must be finite and non-negative");
        break;
    case RigidStatusUnequalLinear:
        for (int k = 0; k < 3; k++)
            if (moments[k] <= rigidKindTolerance()*std::fmax(std::fmax(moments[0], moments[1]), moments[2]))
                throw std::invalid_argument("FreeRotor: a rotor with a zero moment of inertia is linear and needs "
                        "the other two moments equal; got " + detail::fullPrecision(moments[(k + 1)%3]) + " and " +
                        detail::fullPrecision(moments[(k + 2)%3]));
        break;
    default:
        throw std::invalid_argument("FreeRotor: more than one moment of inertia is zero");
    }
    if (shape.kind == RigidKindPoint)
        throw std::invalid_argument("FreeRotor: more than one moment of inertia is zero");
    return shape;
}

inline void FreeRotor::requireInitialized(int status, int representation, double m) {
    if (status == RigidStatusOk)
        return;
    if (status == RigidStatusUnknownRepresentation)
        throw std::invalid_argument("FreeRotor: unknown representation " + std::to_string(representation));
    if (status == RigidStatusThetaOnSeparatrix)
        throw std::invalid_argument("FreeRotor: the theta-series representation does not exist on the separatrix (m = 1)");
    if (status == RigidStatusThetaNotConverged)
        throw std::invalid_argument("FreeRotor: the theta series does not converge at m = " + detail::fullPrecision(m) +
                "; use the elliptic-integral representation this close to the separatrix");
    throw std::invalid_argument("FreeRotor: the rotor could not be built (status " + std::to_string(status) + ")");
}

inline void FreeRotor::validate(const Vector3& moments, const Vector3& omega, const Matrix3& attitude) {
    for (int k = 0; k < 3; k++) {
        if (!std::isfinite(moments[k]) || moments[k] < 0.0)
            throw std::invalid_argument("FreeRotor: moment of inertia " + std::to_string(k) + " is " +
                    detail::fullPrecision(moments[k]) + "; moments must be finite and non-negative");
        if (!std::isfinite(omega[k]))
            throw std::invalid_argument("FreeRotor: angular velocity component " + std::to_string(k) + " is not finite");
        for (int j = 0; j < 3; j++)
            if (!std::isfinite(attitude[k][j]))
                throw std::invalid_argument("FreeRotor: the attitude matrix has a non-finite entry");
    }
    if (orthonormalityError(attitude) > 1e-10)
        throw std::invalid_argument("FreeRotor: the attitude matrix is not orthonormal (|A^T A - 1| = " +
                std::to_string(orthonormalityError(attitude)) + ")");
    if (determinant(attitude) < 0.0)
        throw std::invalid_argument("FreeRotor: the attitude matrix has determinant -1 (a reflection, not a rotation)");
}

inline void FreeRotor::evolve(double t, Vector3& omega, Matrix3& attitude) const {
    if (!std::isfinite(t))
        throw std::invalid_argument("FreeRotor::evolve: the time is not finite");
    double a[3][3];
    rigidRotorEvolve(&rotor, t, omega.data(), a);
    detail::fromArray(a, attitude);
}

} // namespace OpenMMRigid

#endif // OPENMMRIGID_NUMERICS_FREEROTOR_H_
