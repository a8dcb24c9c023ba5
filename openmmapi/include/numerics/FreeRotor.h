#ifndef OPENMMRIGID_NUMERICS_FREEROTOR_H_
#define OPENMMRIGID_NUMERICS_FREEROTOR_H_

/*
 * The exact motion of a free rigid rotor: R. van Zon and J. Schofield, "Numerical implementation of
 * the exact dynamics of free rigid bodies", J. Comput. Phys. 225 (2007) 145-164 (cited below as vZS).
 * ../shared/reference/free-rotor-notes.md restates the algorithm and its delicate cases.
 *
 * Conventions (vZS Section 2): moments are principal moments, omega is the angular velocity in the
 * body frame, the attitude A maps lab vectors to body vectors (v_body = A v_lab). Euler's equations
 * I1 d(omega1)/dt = (I2 - I3) omega2 omega3 (cyclic) and dA/dt = -W(omega) A are solved exactly.
 *
 * Kinds and the formula each uses:
 * - spherical, linear, and any rotation about a principal axis: A(t) = U(-omega t) A(0) (vZS eq. (3.25)).
 * - symmetric: omega precesses about the unique axis (vZS eqs. (3.26)-(3.31)).
 * - asymmetric: omega from Jacobi elliptic functions (vZS eqs. (3.33)-(3.41)); the attitude is
 *   A = Q^T T1'(omega(t)) T2'(psi) B, where Q takes the given axes to internal ones that satisfy the
 *   Jacobi ordering (vZS eq. (3.32), Section 4.3). The angle psi = int Omega dt of eq. (3.20) is
 *   evaluated in one of two exact representations:
 *     ThetaSeries: the complex theta function of vZS eqs. (3.54), (4.3)-(4.8). Its nome
 *       q = exp(-pi K'/K) tends to 1 at the separatrix (m -> 1), where the series stop converging.
 *     EllipticIntegral: eq. (3.20) rewritten as Omega = L/I3 + L (I3 - I1) / (I1 I3 (1 - n sn^2(u|m)))
 *       with n = -I3 (I2 - I1) / (I1 (I3 - I2)) <= 0, so that psi is an incomplete elliptic integral of
 *       the third kind (DLMF 19.2.7), evaluated with Carlson's RF and RJ. It is valid for every m in
 *       [0, 1], the separatrix m = 1 included.
 *   Both are exact to rounding wherever they are defined (checked down to 1 - m = 1e-24 for the
 *   series); Automatic takes the theta series, the cheaper one, for m <= 0.9999 (at most about
 *   eight terms) and the elliptic integral above.
 *
 * Accuracy: omega and A to about 1e-14 relative for times of a few rotation periods; over long times
 * the phase error grows like (rotation angle) x machine epsilon, which is inherent in the rounding of t.
 */

#include "numerics/Elliptic.h"
#include "numerics/Matrix3.h"
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

namespace OpenMMRigid {

class FreeRotor {
public:
    enum Kind { Linear = 0, Spherical = 1, Symmetric = 2, Asymmetric = 3 };
    enum Representation { Automatic = 0, ThetaSeries = 1, EllipticIntegral = 2 };
    /** Automatic uses the theta series up to this elliptic parameter m, the elliptic integral above. */
    static constexpr double automaticThetaSeriesLimit = 0.9999;

    /**
     * Create the rotor from its initial state.
     *
     * @param moments         the three principal moments of inertia, in any order. One may be zero if
     *                        the other two are equal (a linear rotor).
     * @param omega           the angular velocity in the body (principal-axis) frame at t = 0
     * @param attitude        the lab-to-body rotation matrix A(0), orthonormal with determinant +1
     * @param representation  how an asymmetric top evaluates its precession angle (see the file comment)
     * @param checkInput      whether to check that the input is finite and the attitude a rotation. Only
     *                        a caller that guarantees both (the integrator, whose attitudes are kept
     *                        orthonormal and whose momenta are checked every step) may skip it.
     * @throws std::invalid_argument naming the problem, for non-finite or inconsistent input
     */
    FreeRotor(const Vector3& moments, const Vector3& omega, const Matrix3& attitude = identityMatrix(),
              Representation representation = Automatic, bool checkInput = true);

    /**
     * The state at time t (any sign, measured in the time unit of omega).
     *
     * @param t         the time
     * @param omega     on exit, the body-frame angular velocity omega(t)
     * @param attitude  on exit, the attitude matrix A(t)
     */
    void evolve(double t, Vector3& omega, Matrix3& attitude) const;

    /**
     * The state at time t of the rotor that starts from (omega, attitude), written over them: the same
     * result as FreeRotor(moments, omega, attitude).evolve(t, omega, attitude), for the caller that
     * evolves each initial state once (an integrator's drift). An asymmetric top evaluates its theta
     * series at the start and at t in one pass, which makes it cheaper than the two calls.
     *
     * @param checkInput  as for the constructor
     */
    static void advance(const Vector3& moments, Vector3& omega, Matrix3& attitude, double t, bool checkInput = true);

    Kind getKind() const { return kind; }
    static const char* kindName(Kind kind) {
        static const char* names[] = {"linear", "spherical", "symmetric", "asymmetric"};
        return names[kind];
    }
    /** The representation an asymmetric top uses (never Automatic); Automatic for the other kinds. */
    Representation getRepresentation() const { return representation; }
    /** The rotational kinetic energy 1/2 sum_k I_k omega_k^2. */
    double getEnergy() const { return energy; }
    /** The angular momentum in the body frame at t = 0, I_k omega_k. */
    Vector3 getAngularMomentum() const {
        return {moments[0]*omega0[0], moments[1]*omega0[1], moments[2]*omega0[2]};
    }
    const Vector3& getMoments() const { return moments; }
    /** The initial angular velocity; for a linear rotor its component along the axis is removed. */
    const Vector3& getOmega() const { return omega0; }
    const Matrix3& getAttitude() const { return attitude0; }
    /** The elliptic parameter m of an asymmetric top (vZS eq. (3.40)); 0 for the other kinds. */
    double getParameter() const { return m; }

private:
    static constexpr int maxThetaTerms = 64;

    void validate(const Vector3& moments, const Vector3& omega, const Matrix3& attitude) const;
    /** scale = 2^e with x = f 2^e, 1/2 <= f < 1 (as std::frexp splits it), and 1/scale, for normal x > 0. */
    static void powerOfTwoAbove(double x, double& scale, double& inverseScale);
    void classify();
    /** The theta-series values at one argument u (see thetaSeries()). */
    struct ThetaValues {
        double sn, cn, dn, re, im;
    };
    /** The constructor, which with a time t also evaluates the theta series at t into fusedValues. */
    FreeRotor(const Vector3& moments, const Vector3& omega, const Matrix3& attitude, Representation representation,
              bool checkInput, const double* fusedTime);
    void initializeAsymmetric(Representation requested, const double* fusedTime);
    void initializeThetaSeries(double& sn0, double& cn0, double& dn0, const double* fusedTime);
    void initializeEllipticIntegral(double& sn0, double& cn0, double& dn0);
    double precessionAngleExcess(double u, double sn, double cn, double dn) const;
    template <int N>
    void thetaSeries(const double* u, ThetaValues* values) const;
    /** evolve() once sn, cn, dn at u = wp t + eps and cos psi, sin psi are known. */
    void compose(double sn, double cn, double dn, double cosPsi, double sinPsi, Vector3& omega, Matrix3& attitude) const;
    /** cos and sin of the precession angle psi from theta_1 at the time t*frequencyScale (vZS eq. (4.3)). */
    void thetaPrecession(double t, const ThetaValues& value, double& cosPsi, double& sinPsi) const;
    Matrix3 bodyToInvariantFrame(double sn, double cn, double dn) const;

    Vector3 moments, omega0;
    Matrix3 attitude0;
    Kind kind;
    Representation representation;
    double energy;
    bool steady;           // omega along a principal axis (or zero): uniform rotation
    int uniqueAxis;        // symmetric top: the axis whose moment differs
    double symmetricPrecession;  // symmetric top: omega_p = (1 - I_unique / I_perp) omega_unique (eq. (3.26))
    // Asymmetric top, all in internal axes: v_internal[j] = axisSign[j] * v_given[axisOf[j]].
    std::array<int, 3> axisOf;
    std::array<double, 3> axisSign;
    double internalMoments[3];
    // The frequencies below, and |L|, are kept in units of frequencyScale, the power of two near
    // max |omega_k| (see initializeAsymmetric()), and evolve() scales the time instead: neither their
    // products nor the time's underflow or overflow for any finite omega.
    double frequencyScale;
    double angularMomentum;  // |L|
    double w1m, w2m, w3m, wp, m, m1, quarterPeriod, epsilon;
    Matrix3 b;               // B = T1'(omega(0))^T Q A(0)
    // Theta series (vZS eqs. (4.3)-(4.8)).
    int thetaTerms;
    double thetaScale;       // pi / (2K)
    double cr[maxThetaTerms], ci[maxThetaTerms];  // complex theta_1 coefficients
    double oddPowers[maxThetaTerms], evenPowers[maxThetaTerms];  // q^{n(n+1)} and q^{n^2}
    double snScale, cnScale, dnScale;
    double cosPhase1, sinPhase1, phase2 = 0.0;   // cos A1, sin A1 and A2
    // Elliptic integral of the third kind.
    double characteristic;   // n
    double halfPeriodExcess;    // Pi(n|m) - K, the growth of the excess over a half period 2K of u
    double integralPrefactor;   // L (I3 - I1) / (I1 I3 wp)
    double integralAtStart;     // the excess at u = epsilon
    ThetaValues fusedValues;    // advance(): the theta series at its time t
};

inline FreeRotor::FreeRotor(const Vector3& moments, const Vector3& omega, const Matrix3& attitude,
                            Representation requested, bool checkInput) :
        FreeRotor(moments, omega, attitude, requested, checkInput, nullptr) {
}

inline FreeRotor::FreeRotor(const Vector3& moments, const Vector3& omega, const Matrix3& attitude,
                            Representation requested, bool checkInput, const double* fusedTime) :
        moments(moments), omega0(omega), attitude0(attitude), representation(Automatic), steady(false),
        uniqueAxis(-1), symmetricPrecession(0.0), m(0.0) {
    if (requested != Automatic && requested != ThetaSeries && requested != EllipticIntegral)
        throw std::invalid_argument("FreeRotor: unknown representation " + std::to_string((int) requested));
    if (checkInput)
        validate(moments, omega, attitude);
    classify();
    if (kind == Linear)
        for (int k = 0; k < 3; k++)
            if (moments[k] == 0.0)
                omega0[k] = 0.0;
    energy = 0.5*(moments[0]*omega0[0]*omega0[0] + moments[1]*omega0[1]*omega0[1] + moments[2]*omega0[2]*omega0[2]);
    int zeroComponents = (omega0[0] == 0.0) + (omega0[1] == 0.0) + (omega0[2] == 0.0);
    steady = (zeroComponents >= 2 || kind == Spherical || kind == Linear);
    if (kind == Symmetric)
        symmetricPrecession = (1.0 - moments[uniqueAxis]/moments[(uniqueAxis + 1)%3])*omega0[uniqueAxis];
    if (kind == Asymmetric && !steady)
        initializeAsymmetric(requested, fusedTime);
}

inline void FreeRotor::advance(const Vector3& moments, Vector3& omega, Matrix3& attitude, double t, bool checkInput) {
    if (!std::isfinite(t))
        throw std::invalid_argument("FreeRotor::advance: the time is not finite");
    FreeRotor rotor(moments, omega, attitude, Automatic, checkInput, &t);
    if (rotor.kind == Asymmetric && !rotor.steady && rotor.representation == ThetaSeries) {
        double cosPsi, sinPsi;
        rotor.thetaPrecession(t*rotor.frequencyScale, rotor.fusedValues, cosPsi, sinPsi);
        rotor.compose(rotor.fusedValues.sn, rotor.fusedValues.cn, rotor.fusedValues.dn, cosPsi, sinPsi, omega, attitude);
    }
    else
        rotor.evolve(t, omega, attitude);
}

inline void FreeRotor::validate(const Vector3& moments, const Vector3& omega, const Matrix3& attitude) const {
    for (int k = 0; k < 3; k++) {
        if (!std::isfinite(moments[k]) || moments[k] < 0.0)
            throw std::invalid_argument("FreeRotor: moment of inertia " + std::to_string(k) + " is " +
                    std::to_string(moments[k]) + "; moments must be finite and non-negative");
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

inline void FreeRotor::powerOfTwoAbove(double x, double& scale, double& inverseScale) {
    // From the exponent field E of x = 1.f 2^(E - 1023): scale has field E + 1 and 1/scale field 2045 - E,
    // both normal numbers unless x is subnormal or within a factor 4 of the largest double.
    std::uint64_t bits;
    std::memcpy(&bits, &x, sizeof(bits));
    const std::uint64_t field = bits >> 52;
    if (field == 0 || field >= 2045) {
        int exponent;
        std::frexp(x, &exponent);
        scale = std::ldexp(1.0, exponent);
        inverseScale = std::ldexp(1.0, -exponent);
        return;
    }
    const std::uint64_t scaleBits = (field + 1) << 52, inverseBits = (2045 - field) << 52;
    std::memcpy(&scale, &scaleBits, sizeof(scale));
    std::memcpy(&inverseScale, &inverseBits, sizeof(inverseScale));
}

inline void FreeRotor::classify() {
    // Moments that agree to a few ulps are equal: the formulas of the general case stay exact for
    // any distinct moments, so the tolerance only absorbs the rounding of the caller's arithmetic.
    const double tolerance = 8*std::numeric_limits<double>::epsilon()*std::max({moments[0], moments[1], moments[2]});
    auto equal = [&](int i, int j) { return std::fabs(moments[i] - moments[j]) <= tolerance; };
    int zeros = 0, zeroAxis = -1;
    for (int k = 0; k < 3; k++)
        if (moments[k] <= tolerance) {
            zeros++;
            zeroAxis = k;
        }
    if (zeros > 1)
        throw std::invalid_argument("FreeRotor: more than one moment of inertia is zero");
    if (zeros == 1) {
        if (!equal((zeroAxis + 1)%3, (zeroAxis + 2)%3))
            throw std::invalid_argument("FreeRotor: a rotor with a zero moment of inertia is linear and needs "
                    "the other two moments equal; got " + std::to_string(moments[(zeroAxis + 1)%3]) + " and " +
                    std::to_string(moments[(zeroAxis + 2)%3]));
        moments[zeroAxis] = 0.0;
        kind = Linear;
        return;
    }
    if (equal(0, 1) && equal(1, 2))
        kind = Spherical;
    else if (equal(0, 1))
        kind = Symmetric, uniqueAxis = 2;
    else if (equal(1, 2))
        kind = Symmetric, uniqueAxis = 0;
    else if (equal(0, 2))
        kind = Symmetric, uniqueAxis = 1;
    else
        kind = Asymmetric;
}

inline void FreeRotor::initializeAsymmetric(Representation requested, const double* fusedTime) {
    // Put the middle moment on the second axis by a cyclic (proper) permutation, then apply the
    // Jacobi ordering of vZS eq. (3.32): if needed, swap axes 1 and 3 and flip axis 2 (vZS eq. (4.10)).
    int middle = 0;
    for (int k = 0; k < 3; k++) {
        int below = (moments[(k + 1)%3] < moments[k]) + (moments[(k + 2)%3] < moments[k]);
        if (below == 1)
            middle = k;
    }
    std::array<int, 3> cyclic = {(middle + 2)%3, middle, (middle + 1)%3};
    const double ix = moments[cyclic[0]], iy = moments[cyclic[1]], iz = moments[cyclic[2]];
    // Everything below is computed for omega / 2^e with 2^e near max|omega_k| (so that no square
    // underflows or overflows, and the division is exact), and the quantities with units of
    // frequency are scaled back at the end.
    // A subnormal omega is first multiplied by 2^600, so that 1/2^e is a double too.
    const double largest = std::max({std::fabs(omega0[0]), std::fabs(omega0[1]), std::fabs(omega0[2])});
    const double prescale = (largest < std::numeric_limits<double>::min() ? 0x1p600 : 1.0);
    double scale, inverseScale;
    powerOfTwoAbove(largest*prescale, scale, inverseScale);
    scale /= prescale;
    const double scaledOmega[3] = {omega0[0]*prescale*inverseScale, omega0[1]*prescale*inverseScale, omega0[2]*prescale*inverseScale};
    // 2E Iy - L^2 = sum_k I_k w_k^2 (Iy - I_k), free of the cancellation of the difference.
    double twoEIyMinusL2 = 0.0;
    for (int k = 0; k < 3; k++)
        twoEIyMinusL2 += moments[k]*scaledOmega[k]*scaledOmega[k]*(iy - moments[k]);
    bool flip = (twoEIyMinusL2 > 0.0 && ix < iz) || (twoEIyMinusL2 < 0.0 && ix > iz);
    if (flip) {
        axisOf = {cyclic[2], cyclic[1], cyclic[0]};
        axisSign = {1.0, -1.0, 1.0};
    }
    else {
        axisOf = cyclic;
        axisSign = {1.0, 1.0, 1.0};
    }
    double w0[3];
    for (int j = 0; j < 3; j++) {
        internalMoments[j] = moments[axisOf[j]];
        w0[j] = axisSign[j]*scaledOmega[axisOf[j]];
    }
    const double i1 = internalMoments[0], i2 = internalMoments[1], i3 = internalMoments[2];
    // L^2 - 2E I_j = sum_k I_k w_k^2 (I_k - I_j) (notes: "Where the formulas are delicate").
    double l2MinusTwoEI1 = 0.0, l2MinusTwoEI3 = 0.0, l2 = 0.0;
    for (int k = 0; k < 3; k++) {
        double weight = internalMoments[k]*w0[k]*w0[k];
        l2MinusTwoEI1 += weight*(internalMoments[k] - i1);
        l2MinusTwoEI3 += weight*(internalMoments[k] - i3);
        l2 += weight*internalMoments[k];
    }
    angularMomentum = std::sqrt(l2);
    // vZS eqs. (3.36)-(3.41). sgn(0) is taken as +1; any fixed choice satisfies Euler's equations.
    const double sign1 = (w0[0] < 0.0 ? -1.0 : 1.0), sign3 = (w0[2] < 0.0 ? -1.0 : 1.0);
    w1m = sign1*std::sqrt(std::max(0.0, l2MinusTwoEI3/(i1*(i1 - i3))));
    w2m = -sign1*std::sqrt(std::max(0.0, l2MinusTwoEI3/(i2*(i2 - i3))));
    w3m = sign3*std::sqrt(std::max(0.0, l2MinusTwoEI1/(i3*(i3 - i1))));
    wp = (i2 > i3 ? 1.0 : -1.0)*sign3*std::sqrt(std::max(0.0, l2MinusTwoEI1*(i3 - i2)/(i1*i2*i3)));
    double numerator = l2MinusTwoEI3*(i1 - i2), denominator = l2MinusTwoEI1*(i3 - i2);
    m = std::clamp(numerator/denominator, 0.0, 1.0);
    // 1 - m = (L^2 - 2E I2)(I3 - I1) / ((L^2 - 2E I1)(I3 - I2)), again without cancellation.
    double l2MinusTwoEI2 = 0.0;
    for (int k = 0; k < 3; k++)
        l2MinusTwoEI2 += internalMoments[k]*w0[k]*w0[k]*(internalMoments[k] - i2);
    m1 = std::clamp(l2MinusTwoEI2*(i3 - i1)/denominator, 0.0, 1.0);
    if (!(m > 0.0) || w1m == 0.0) {
        // L along axis 3 to within the range of doubles: the precession amplitude is below
        // 1e-300 |omega|, and the uniform rotation is exact to that level.
        steady = true;
        m = 0.0;
        return;
    }

    // The initial argument: sn(eps) = w2/w2m, cn(eps) = w1/w1m, dn(eps) = w3/w3m (vZS eq. (3.42)),
    // with all three ratios used so that eps keeps full precision near the turning points.
    // sn0, cn0 and dn0 are then replaced by the values the chosen representation gives at eps.
    double sn0 = std::clamp(w0[1]/w2m, -1.0, 1.0);
    double cn0 = std::clamp(w0[0]/w1m, 0.0, 1.0);
    double dn0 = std::clamp(w0[2]/w3m, 0.0, 1.0);
    if (cn0*cn0 == 0.0 && dn0*dn0 == 0.0) {
        // omega along the middle axis to within the range of doubles: the unstable steady rotation.
        steady = true;
        return;
    }
    if (requested == Automatic)
        requested = (m <= automaticThetaSeriesLimit ? ThetaSeries : EllipticIntegral);
    if (requested == ThetaSeries && m1 == 0.0)
        throw std::invalid_argument("FreeRotor: the theta-series representation does not exist on the separatrix (m = 1)");
    representation = requested;
    // Each representation computes eps = F(sn0 | m) (vZS eq. (3.42)) and evaluates sn, cn, dn at u = eps
    // in its own way; building B from those
    // values (rather than from the given omega) makes evolve(0) return A(0) to rounding.
    if (representation == ThetaSeries) {
        // advance()'s time in the unit of the scaled frequencies (exact: scale is a power of two).
        double scaledTime = (fusedTime == nullptr ? 0.0 : *fusedTime*scale);
        initializeThetaSeries(sn0, cn0, dn0, fusedTime == nullptr ? nullptr : &scaledTime);
    }
    else
        initializeEllipticIntegral(sn0, cn0, dn0);

    // B = T1'(omega(0))^T Q A(0) (notes, initialization step 4).
    Matrix3 qa;
    for (int j = 0; j < 3; j++)
        for (int c = 0; c < 3; c++)
            qa[j][c] = axisSign[j]*attitude0[axisOf[j]][c];
    b = multiplyTransposed(bodyToInvariantFrame(sn0, cn0, dn0), qa);
    frequencyScale = scale;
}

inline void FreeRotor::initializeThetaSeries(double& sn0, double& cn0, double& dn0, const double* fusedTime) {
    const double i1 = internalMoments[0], i3 = internalMoments[2];
    // The nome q = exp(-pi K'/K) by Jacobi's series q = l + 2 l^5 + 15 l^9 + 150 l^13 + ... with
    // l = (1 - m1^(1/4)) / (2 (1 + m1^(1/4))) (Abramowitz & Stegun 17.3.21), which converges fast for
    // m <= 1/2 (l <= 0.044). Above, the same series in m gives the complementary nome q' = exp(-pi K/K'),
    // and ln q ln q' = pi^2. Then K = (pi/2) theta_3(0|q)^2 (DLMF 20.9.2): no AGM is needed.
    auto jacobiNome = [](double fourthRoot, double oneMinusParameter) {
        // 1 - p^(1/4) = (1 - p) / ((1 + p^(1/2))(1 + p^(1/4))), free of cancellation for p near 1.
        double l = oneMinusParameter/((1.0 + fourthRoot*fourthRoot)*(1.0 + fourthRoot))/(2.0*(1.0 + fourthRoot));
        double l4 = l*l*l*l;
        return l*(1.0 + l4*(2.0 + l4*(15.0 + l4*(150.0 + l4*(1707.0 + l4*(20910.0 + l4*268616.0))))));
    };
    const double nome = (m <= 0.5 ? jacobiNome(std::sqrt(std::sqrt(m1)), m) :
            std::exp(M_PI*M_PI/std::log(jacobiNome(std::sqrt(std::sqrt(m)), m1))));
    // The powers q^{n(n+1)} and q^{n^2}, and theta_2, theta_3, theta_4 at zero (DLMF 20.2.2-20.2.4; theta_2
    // without its factor 2 q^{1/4}, which thetaSeries() drops from theta_1 as well), summed until
    // q^{n^2} < eps/4. The theta_1 coefficients below fall at least as fast relative to their first
    // term: |eta| <= K' makes |x| <= pi K' / 2K = -ln(q) / 2, so q^{n(n+1)} e^{2n|x|} <= q^{n^2}.
    // The same terms therefore serve every series.
    double theta2 = 0.0, theta3 = 1.0, theta4 = 1.0;
    {
        double oddPower = 1.0, oddStep = nome*nome;  // q^{n(n+1)} and q^{2(n+1)}
        double evenPower = 1.0, evenStep = nome;     // q^{n^2} and q^{2n+1}
        for (int n = 0;; n++) {
            if (n == maxThetaTerms)
                throw std::invalid_argument("FreeRotor: the theta series does not converge at m = " + std::to_string(m) +
                        "; use the elliptic-integral representation this close to the separatrix");
            oddPowers[n] = oddPower;
            evenPowers[n] = evenPower;
            theta2 += oddPower;
            if (n > 0) {
                theta3 += 2.0*evenPower;
                theta4 += (n%2 == 0 ? 2.0 : -2.0)*evenPower;
            }
            thetaTerms = n + 1;
            if (n > 0 && evenPower < 0.25*std::numeric_limits<double>::epsilon())
                break;
            oddPower *= oddStep;
            oddStep *= nome*nome;
            evenPower *= evenStep;
            evenStep *= nome*nome;
        }
    }
    // K = (pi/2) theta_3(0|q)^2 (DLMF 20.9.2)
    quarterPeriod = 0.5*M_PI*theta3*theta3;
    thetaScale = M_PI/(2.0*quarterPeriod);
    // eta = sgn(w3m) K' - F(I3 w3m / L | 1 - m) (vZS eq. (3.47)). With x = I3 w3m / L the difference
    // K' - F(|x| | m1) is F of the complementary amplitude (DLMF 19.11.3), which by the homogeneity
    // of RF is sqrt(c) RF(m L3^2, m L^2, m L3^2 + c) with L3 = I3 w3m and c = L^2 - L3^2 = (I1 w1m)^2
    // (at u = 0, where omega = (w1m, 0, w3m)). This form has no cancellation when L is near axis 3.
    // The same call gives eps = sn0 RF(cn0^2, dn0^2, 1) (DLMF 19.25.5), the two integrals side by side.
    const double l3 = i3*w3m, c = (i1*w1m)*(i1*w1m);
    double rx[2] = {m*l3*l3, cn0*cn0}, ry[2] = {m*angularMomentum*angularMomentum, dn0*dn0}, rz[2] = {m*l3*l3 + c, 1.0}, rf[2];
    Special::detail::carlsonRFLockstep<2>(rx, ry, rz, rf);
    const double eta = (w3m < 0.0 ? -1.0 : 1.0)*std::sqrt(c)*rf[0];
    epsilon = sn0*rf[1];
    // Theta coefficients (notes, initialization step 9) with the common factor q^{1/4} dropped, since
    // only the phase of theta_1 enters psi: cr = 2 (-1)^n q^{n(n+1)} cosh((2n+1)x) and
    // ci = -2 (-1)^n q^{n(n+1)} sinh((2n+1)x), x = pi eta / 2K. The hyperbolic functions are advanced
    // by the addition theorem from sinh x (taken from expm1), so that sinh keeps its relative accuracy
    // when x is small (L near axis 3). The same powers q^{n(n+1)} and q^{n^2} give the real theta
    // functions for sn, cn, dn.
    const double x = thetaScale*eta;
    const double expm1x = std::expm1(x);
    const double sinhX = 0.5*expm1x*(1.0 + 1.0/(1.0 + expm1x)), coshX = std::sqrt(1.0 + sinhX*sinhX);
    const double sinh2X = 2.0*sinhX*coshX, cosh2X = 1.0 + 2.0*sinhX*sinhX;
    double sinhK = sinhX, coshK = coshX;  // of (2n+1)x
    // A2 (vZS eq. (3.53), (4.8)): L/I1 + (pi wp / 2K) times the bracket [coth(x) - 2 sum q^{2n}/(1 - q^{2n})
    // (xi^n - xi^-n)], which is i theta_1'/theta_1 at i x (DLMF 20.5.10). Written with the theta series
    // itself it is sum (2n+1) cr / (-sum ci): the same few terms instead of a Lambert series in q.
    double derivative = 0.0, value = 0.0;
    for (int n = 0; n < thetaTerms; n++) {
        double sign = (n%2 == 0 ? 2.0 : -2.0);
        cr[n] = sign*oddPowers[n]*coshK;
        ci[n] = -sign*oddPowers[n]*sinhK;
        derivative += (2*n + 1)*cr[n];
        value -= ci[n];
        double nextSinh = sinhK*cosh2X + coshK*sinh2X;
        coshK = coshK*cosh2X + sinhK*sinh2X;
        sinhK = nextSinh;
    }
    // The Jacobi functions' scales (DLMF 22.2.4-22.2.6).
    snScale = theta3/theta2;
    cnScale = theta4/theta2;
    dnScale = theta4/theta3;
    phase2 = angularMomentum/i1 + thetaScale*wp*derivative/value;
    // At u = eps, and for advance() at u = wp t + eps with t scaled as evolve() scales it.
    ThetaValues values[2];
    if (fusedTime != nullptr) {
        const double arguments[2] = {epsilon, wp*(*fusedTime) + epsilon};
        thetaSeries<2>(arguments, values);
        fusedValues = values[1];
    }
    else
        thetaSeries<1>(&epsilon, values);
    sn0 = values[0].sn;
    cn0 = values[0].cn;
    dn0 = values[0].dn;
    // A1 = arg theta_1(eps) (vZS eq. (4.5)); only its cosine and sine are needed.
    double size = std::sqrt(values[0].re*values[0].re + values[0].im*values[0].im);
    cosPhase1 = values[0].re/size;
    sinPhase1 = values[0].im/size;
}

/**
 * The theta series at u[0], ..., u[N-1], each from one sine and cosine of zeta = pi u / 2K: the Jacobi
 * functions sn, cn, dn (DLMF 22.2.4-22.2.6 with the theta functions of DLMF 20.2.1-20.2.4) and the real
 * and imaginary parts of theta_1 at pi (u - i eta) / 2K (vZS eq. (4.4)), up to a common positive factor.
 * The N sums run side by side, so that their multiplications overlap.
 */
template <int N>
inline void FreeRotor::thetaSeries(const double* u, ThetaValues* values) const {
    // sin and cos of k zeta for odd k (so, co) and even k (se, ce), each advanced by 2 zeta: two
    // independent recurrences for each argument.
    double so[N], co[N], se[N], ce[N], s2[N], c2[N];
    double theta1[N], theta2[N], theta3[N], theta4[N], re[N], im[N];
    for (int j = 0; j < N; j++) {
        const double zeta = thetaScale*u[j];
        so[j] = std::sin(zeta);
        co[j] = std::cos(zeta);
        s2[j] = se[j] = 2.0*so[j]*co[j];
        c2[j] = ce[j] = (co[j] - so[j])*(co[j] + so[j]);
        theta1[j] = oddPowers[0]*so[j];
        theta2[j] = oddPowers[0]*co[j];
        theta3[j] = theta4[j] = 1.0;
        re[j] = cr[0]*so[j];
        im[j] = ci[0]*co[j];
    }
    for (int n = 1; n < thetaTerms; n++) {
        const double signedOdd = (n%2 == 0 ? oddPowers[n] : -oddPowers[n]);
        const double even = 2.0*evenPowers[n], signedEven = (n%2 == 0 ? even : -even);
        for (int j = 0; j < N; j++) {
            double nextOdd = so[j]*c2[j] + co[j]*s2[j];
            co[j] = co[j]*c2[j] - so[j]*s2[j];
            so[j] = nextOdd;
            // k = 2n
            theta3[j] += even*ce[j];
            theta4[j] += signedEven*ce[j];
            // k = 2n + 1
            re[j] += cr[n]*so[j];
            im[j] += ci[n]*co[j];
            theta1[j] += signedOdd*so[j];
            theta2[j] += oddPowers[n]*co[j];
            double nextEven = se[j]*c2[j] + ce[j]*s2[j];
            ce[j] = ce[j]*c2[j] - se[j]*s2[j];
            se[j] = nextEven;
        }
    }
    for (int j = 0; j < N; j++) {
        values[j].sn = snScale*theta1[j]/theta4[j];
        values[j].cn = cnScale*theta2[j]/theta4[j];
        values[j].dn = dnScale*theta3[j]/theta4[j];
        values[j].re = re[j];
        values[j].im = im[j];
    }
}

inline void FreeRotor::initializeEllipticIntegral(double& sn0, double& cn0, double& dn0) {
    const double i1 = internalMoments[0], i2 = internalMoments[1], i3 = internalMoments[2];
    quarterPeriod = Special::ellipticK(m, m1);
    epsilon = Special::ellipticFFromJacobi(sn0, cn0*cn0, dn0*dn0);
    characteristic = -i3*(i2 - i1)/(i1*(i3 - i2));
    integralPrefactor = angularMomentum*(i3 - i1)/(i1*i3*wp);
    // The excess of Pi(n|m) over K over a half period: (n/3) RJ(0, m1, 1, 1 - n) (DLMF 19.25.2 with DLMF 19.25.14).
    halfPeriodExcess = (m1 == 0.0 ? 0.0 : characteristic/3.0*Special::carlsonRJ(0.0, m1, 1.0, 1.0 - characteristic));
    Special::jacobiElliptic(epsilon, m, m1, sn0, cn0, dn0);
    integralAtStart = precessionAngleExcess(epsilon, sn0, cn0, dn0);
}

/**
 * The part of int_0^u du' / (1 - n sn^2(u')) beyond u itself, for any real u. Since the
 * RF term of Pi(n; am(u)|m) is exactly u on [-K, K] (DLMF 19.25.5), only the RJ term remains:
 * reduce u = 2K j + r with |r| <= K; the excess is 2 j (n/3) RJ(0, m1, 1, 1 - n) plus
 * (n/3) sn^3(r) RJ(cn^2, dn^2, 1, 1 - n sn^2) (DLMF 19.25.14), and sn(r) = (-1)^j sn(u).
 * On the separatrix (m = 1, K infinite) the integral is elementary: with nu = -n,
 * int_0^u du' / (1 + nu tanh^2 u') = (u + sqrt(nu) atan(sqrt(nu) tanh u)) / (1 + nu).
 */
inline double FreeRotor::precessionAngleExcess(double u, double sn, double cn, double dn) const {
    const double n = characteristic;
    if (m1 == 0.0) {
        double nu = -n, root = std::sqrt(nu);
        return (root*std::atan(root*sn) - nu*u)/(1.0 + nu);
    }
    double halfPeriods = std::nearbyint(u/(2.0*quarterPeriod));
    double r = (std::fmod(halfPeriods, 2.0) == 0.0 ? sn : -sn);
    return 2.0*halfPeriods*halfPeriodExcess + n/3.0*r*r*r*Special::carlsonRJ(cn*cn, dn*dn, 1.0, 1.0 - n*r*r);
}

/** T1'(omega) of vZS eq. (3.13): its columns are e1, e2 and L/|L| in the internal body frame. */
inline Matrix3 FreeRotor::bodyToInvariantFrame(double sn, double cn, double dn) const {
    // L = (I1 w1m cn, I2 w2m sn, I3 w3m dn) (vZS eqs. (3.33)-(3.35)), in units of frequencyScale.
    double l1 = internalMoments[0]*w1m*cn, l2 = internalMoments[1]*w2m*sn, l3 = internalMoments[2]*w3m*dn;
    double perp = std::sqrt(l1*l1 + l2*l2);
    double inverseL = 1.0/angularMomentum, inversePerp = 1.0/perp, l3Ratio = l3*inverseL*inversePerp;
    return {{{l1*l3Ratio, -l2*inversePerp, l1*inverseL},
             {l2*l3Ratio, l1*inversePerp, l2*inverseL},
             {-perp*inverseL, 0.0, l3*inverseL}}};
}

inline void FreeRotor::evolve(double t, Vector3& omega, Matrix3& attitude) const {
    if (!std::isfinite(t))
        throw std::invalid_argument("FreeRotor::evolve: the time is not finite");
    if (steady) {
        omega = omega0;
        attitude = multiply(rotationMatrix(scaled(omega0, -t)), attitude0);
        return;
    }
    if (kind == Symmetric) {
        // vZS eqs. (3.26)-(3.31): omega(t) = U(-wp t e) omega(0), A(t) = U(-wp t e) U(-L(0) t / I_perp) A(0).
        Vector3 axis = {0.0, 0.0, 0.0};
        axis[uniqueAxis] = -symmetricPrecession*t;
        Matrix3 precession = rotationMatrix(axis);
        double perpendicular = moments[(uniqueAxis + 1)%3];
        Vector3 spin = scaled(getAngularMomentum(), -t/perpendicular);
        omega = multiply(precession, omega0);
        attitude = multiply(precession, multiply(rotationMatrix(spin), attitude0));
        return;
    }
    // Asymmetric top: vZS eqs. (3.33)-(3.35), then A = Q^T T1'(omega(t)) T2'(psi) B.
    const double scaledTime = t*frequencyScale;  // exact: frequencyScale is a power of two
    double u = wp*scaledTime + epsilon;
    double cosPsi, sinPsi;
    if (representation == ThetaSeries) {
        ThetaValues value;
        thetaSeries<1>(&u, &value);
        thetaPrecession(scaledTime, value, cosPsi, sinPsi);
        compose(value.sn, value.cn, value.dn, cosPsi, sinPsi, omega, attitude);
    }
    else {
        double sn, cn, dn;
        Special::jacobiElliptic(u, m, m1, sn, cn, dn);
        // psi = (L/I3) t + P (Pi(u) - Pi(eps)) with Pi(u) = u + excess(u) and P wp = L (I3 - I1)/(I1 I3).
        double psi = angularMomentum/internalMoments[0]*scaledTime + integralPrefactor*(precessionAngleExcess(u, sn, cn, dn) - integralAtStart);
        compose(sn, cn, dn, std::cos(psi), std::sin(psi), omega, attitude);
    }
}

inline void FreeRotor::thetaPrecession(double t, const ThetaValues& value, double& cosPsi, double& sinPsi) const {
    // psi = A1 + A2 t - arg theta_1(u) (vZS eq. (4.3); notes, evolution step 2), the angle sums done on
    // cosines and sines.
    double c2 = std::cos(phase2*t), s2 = std::sin(phase2*t), size = std::sqrt(value.re*value.re + value.im*value.im);
    double c = cosPhase1*c2 - sinPhase1*s2, s = sinPhase1*c2 + cosPhase1*s2;  // of A1 + A2 t
    cosPsi = (c*value.re + s*value.im)/size;
    sinPsi = (s*value.re - c*value.im)/size;
}

inline void FreeRotor::compose(double sn, double cn, double dn, double cosPsi, double sinPsi, Vector3& omega,
                               Matrix3& attitude) const {
    Vector3 w = {w1m*cn*frequencyScale, w2m*sn*frequencyScale, w3m*dn*frequencyScale};
    Matrix3 t1 = bodyToInvariantFrame(sn, cn, dn);
    // T1' T2' with T2' = [[cos, sin, 0], [-sin, cos, 0], [0, 0, 1]] (vZS eq. (3.14)).
    Matrix3 rotation;
    for (int i = 0; i < 3; i++) {
        rotation[i][0] = t1[i][0]*cosPsi - t1[i][1]*sinPsi;
        rotation[i][1] = t1[i][0]*sinPsi + t1[i][1]*cosPsi;
        rotation[i][2] = t1[i][2];
    }
    Matrix3 internalAttitude = multiply(rotation, b);
    for (int j = 0; j < 3; j++) {
        omega[axisOf[j]] = axisSign[j]*w[j];
        for (int c = 0; c < 3; c++)
            attitude[axisOf[j]][c] = axisSign[j]*internalAttitude[j][c];
    }
}

} // namespace OpenMMRigid

#endif // OPENMMRIGID_NUMERICS_FREEROTOR_H_
