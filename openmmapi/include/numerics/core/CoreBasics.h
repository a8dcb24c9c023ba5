/*
 * The numerics core, part 1: the few helpers every other core file uses (a clamp, 3 x 3 products,
 * Rodrigues' rotation). Plain C on doubles, shared by every target: see numerics/RigidCore.h for the
 * rules the core files follow and the prelude each target puts in front of them.
 *
 * Matrices are double[3][3], row-major: m[i][j] is row i, column j. Everything is exact up to the
 * rounding of the few products and sums it performs.
 */
#ifndef OPENMMRIGID_CORE_BASICS_H_
#define OPENMMRIGID_CORE_BASICS_H_

/** The status every core function that can fail returns (0 is success). */
enum RigidStatus {
    RigidStatusOk = 0,
    RigidStatusNegativeMoment = 1,       /* a moment of inertia is negative or not a number */
    RigidStatusTwoZeroMoments = 2,       /* two moments are zero but not the third */
    RigidStatusUnequalLinear = 3,        /* one moment is zero and the other two differ */
    RigidStatusThetaOnSeparatrix = 4,    /* the theta series was requested at m = 1, where it does not exist */
    RigidStatusThetaNotConverged = 5,    /* the theta series needs more terms than the core allows */
    RigidStatusUnknownRepresentation = 6 /* a representation code that is not one of RigidRepresentation */
};

/** pi to double precision (the nearest double, as M_PI, which strict C99 does not define). */
RIGID_FUNCTION double rigidPi(void) {
    return 3.14159265358979323846;
}

/** The machine epsilon of double, 2^-52. */
RIGID_FUNCTION double rigidEpsilon(void) {
    return 0x1p-52;
}

/** x clamped to [low, high], as std::clamp does it (a NaN stays NaN). */
RIGID_FUNCTION double rigidClamp(double x, double low, double high) {
    return (x < low ? low : (high < x ? high : x));
}

/** max(0, x), as std::max(0.0, x) computes it (0 for a NaN, +0 for -0). */
RIGID_FUNCTION double rigidPositivePart(double x) {
    return (0.0 < x ? x : 0.0);
}

RIGID_FUNCTION double rigidMax3(double a, double b, double c) {
    double ab = (a < b ? b : a);
    return (ab < c ? c : ab);
}

RIGID_FUNCTION double rigidMax4(double a, double b, double c, double d) {
    const double abc = rigidMax3(a, b, c);
    return (abc < d ? d : abc);
}

/** c = a b (c must not alias a or b). */
RIGID_FUNCTION void rigidMultiply(double a[3][3], double b[3][3], double c[3][3]) {
    int i, j;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++)
            c[i][j] = a[i][0]*b[0][j] + a[i][1]*b[1][j] + a[i][2]*b[2][j];
}

/** c = a^T b (c must not alias a or b). */
RIGID_FUNCTION void rigidMultiplyTransposed(double a[3][3], double b[3][3], double c[3][3]) {
    int i, j;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++)
            c[i][j] = a[0][i]*b[0][j] + a[1][i]*b[1][j] + a[2][i]*b[2][j];
}

/** w = a v (w must not alias v). */
RIGID_FUNCTION void rigidMultiplyVector(double a[3][3], const double* v, double* w) {
    int i;
    for (i = 0; i < 3; i++)
        w[i] = a[i][0]*v[0] + a[i][1]*v[1] + a[i][2]*v[2];
}

/**
 * |x| for a 3-vector without overflow or underflow: the largest |x_k| is factored out before the
 * squares are summed (as libstdc++ computes the three-argument std::hypot).
 */
RIGID_FUNCTION double rigidNorm(const double* x) {
    const double a = fabs(x[0]), b = fabs(x[1]), c = fabs(x[2]);
    const double largest = rigidMax3(a, b, c);
    if (largest == 0.0)
        return 0.0;
    return largest*sqrt((a/largest)*(a/largest) + (b/largest)*(b/largest) + (c/largest)*(c/largest));
}

/** The largest |x| that rigidSinCosReduced() takes (then |k| < 2^17 in its reduction, far within the 2^20 its splitting of pi/2 allows). */
#define RIGID_SIN_COS_LIMIT 1.0e5

/**
 * sin x and cos x for |x| <= RIGID_SIN_COS_LIMIT, by the same operations on every platform and in
 * every lane of a loop (no branch, no library call, so that loops over bodies vectorize).
 * Reduction: k is the integer nearest 2x/pi, found by adding 1.5 * 2^52 (which leaves it in the low
 * bits of the sum, from which the quadrant k mod 4 is read), and r = x - k pi/2 with pi/2 split into
 * p1 + p2 + p3, p1 and p2 of 33 significant bits (so k p1 and k p2 are exact) and p3 of 53, 119 bits
 * in all; r is kept as a double and a small correction lo (the rounding of the subtraction of k p2,
 * found exactly, less k p3). sin r and cos r on |r| <= pi/4 (a little more where 2x/pi rounds) are
 * their Taylor series to r^17 and r^18 (the first terms left out are below 1e-19), by Horner's rule
 * in z = r^2, with lo added to first order; cos r = (1 - z/2) + z^2 C(z) adds back the rounding error
 * of w = 1 - z/2, found exactly as (1 - w) - z/2. (Not "half": a type in OpenCL C.)
 * The quadrant then permutes and signs them: sin(r + k pi/2) = sin r, cos r, -sin r, -cos r for
 * k mod 4 = 0, 1, 2, 3. Within one ulp of the exact values (TestSpecialFunctions: at most 0.83 ulp
 * against long double on 890000 arguments); signed zeros, subnormals and NaN pass through.
 */
RIGID_HOT_FUNCTION void rigidSinCosReduced(double x, double* s, double* c) {
    const double shifter = 6755399441055744.0;  /* 1.5 * 2^52 */
    const double shifted = x*0.63661977236758138 + shifter;  /* 2/pi */
    const RigidUInt64 quadrant = rigidDoubleBits(shifted) & 3;
    const double k = shifted - shifter;
    /* r = x - k pi/2 as hi + lo: x - k p1 is exact (Sterbenz), and so is the error of taking k p2 from it */
    const double exact = x - k*1.5707963267341256, p2 = k*6.077100506303966e-11;
    const double r = exact - p2;
    const double lo = ((exact - r) - p2) - k*2.0222662487959506e-21;
    const double z = r*r;
    /* 1/3!, 1/5!, ..., 1/17! with alternating signs, and 1/4!, ..., 1/18! */
    const double sinPart = -0.16666666666666666 + z*(0.008333333333333333 + z*(-0.0001984126984126984 +
        z*(2.7557319223985893e-06 + z*(-2.505210838544172e-08 + z*(1.6059043836821613e-10 +
        z*(-7.647163731819816e-13 + z*2.8114572543455206e-15))))));
    const double cosPart = 0.041666666666666664 + z*(-0.001388888888888889 + z*(2.48015873015873e-05 +
        z*(-2.755731922398589e-07 + z*(2.08767569878681e-09 + z*(-1.1470745597729725e-11 +
        z*(4.779477332387385e-14 + z*(-1.5619206968586225e-16)))))));
    const double halfZ = 0.5*z, w = 1.0 - halfZ;
    /* sin(r + lo) = sin r + lo cos r and cos(r + lo) = cos r - lo sin r to first order in lo (|lo| <= ulp(r)) */
    const double sinR = (x == 0.0 ? x : r + (r*z*sinPart + lo*w));  /* x itself keeps the sign of a zero */
    const double cosR = w + (((1.0 - w) - halfZ) + (z*z*cosPart - r*lo));
    const double swappedSin = ((quadrant & 1) != 0 ? cosR : sinR), swappedCos = ((quadrant & 1) != 0 ? sinR : cosR);
    *s = ((quadrant & 2) != 0 ? -swappedSin : swappedSin);
    *c = (((quadrant + 1) & 2) != 0 ? -swappedCos : swappedCos);
}

/** sin x and cos x: rigidSinCosReduced() for |x| <= RIGID_SIN_COS_LIMIT, else (and for infinities and NaN) the library's sin and cos. */
RIGID_HOT_FUNCTION void rigidSinCos(double x, double* s, double* c) {
    if (fabs(x) <= RIGID_SIN_COS_LIMIT)
        rigidSinCosReduced(x, s, c);
    else {
        *s = sin(x);
        *c = cos(x);
    }
}

/**
 * Rodrigues' formula: U(x) = exp(W(x)) with W(x) v = x cross v, the rotation by the angle |x| about
 * x/|x| (van Zon & Schofield (2007) eq. (3.24)). Written with sin(a)/a and (1 - cos a)/a^2 in forms
 * that stay accurate for small angles.
 */
RIGID_FUNCTION void rigidRotationMatrix(const double* x, double r[3][3]) {
    const double angle = rigidNorm(x);
    double sinc, versine;  /* sin(a)/a and (1 - cos(a))/a^2 */
    int i, j;
    if (angle < 1e-4) {
        const double a2 = angle*angle;
        sinc = 1.0 - a2/6.0*(1.0 - a2/20.0);
        versine = 0.5*(1.0 - a2/12.0*(1.0 - a2/30.0));
    }
    else {
        const double halfSin = sin(0.5*angle);
        sinc = sin(angle)/angle;
        versine = 2.0*halfSin*halfSin/(angle*angle);
    }
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++)
            r[i][j] = (i == j ? 1.0 : 0.0) + versine*(x[i]*x[j] - (i == j ? angle*angle : 0.0));
    /* W(x) = [[0,-x3,x2],[x3,0,-x1],[-x2,x1,0]] */
    r[0][1] -= sinc*x[2]; r[1][0] += sinc*x[2];
    r[0][2] += sinc*x[1]; r[2][0] -= sinc*x[1];
    r[1][2] -= sinc*x[0]; r[2][1] += sinc*x[0];
}

/**
 * One Newton-Schulz step towards the nearest rotation, a <- a (3 - a^T a) / 2: it removes the
 * rounding drift an attitude gathers over many drifts (the error e of a^T a = 1 + e becomes O(e^2)).
 */
RIGID_FUNCTION void rigidReorthonormalize(double a[3][3]) {
    double g[3][3], correction[3][3], result[3][3];
    int i, j;
    rigidMultiplyTransposed(a, a, g);
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++)
            correction[i][j] = 0.5*((i == j ? 3.0 : 0.0) - g[i][j]);
    rigidMultiply(a, correction, result);
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++)
            a[i][j] = result[i][j];
}

/** The body-frame angular velocity omega_k = L_k / I_k from the body-frame angular momentum; a zero moment (the axis of a line) carries none. */
RIGID_FUNCTION void rigidAngularVelocity(const double* moments, const double* angularMomentum, double* omega) {
    int k;
    for (k = 0; k < 3; k++)
        omega[k] = (moments[k] > 0.0 ? angularMomentum[k]/moments[k] : 0.0);
}

/** Whether a body's moments were raised: some ratio s_k = I'_k / I_k of its raised to its particles' moments is not 1. */
RIGID_FUNCTION int rigidMomentsRaised(const double* scale) {
    return scale[0] != 1.0 || scale[1] != 1.0 || scale[2] != 1.0;
}

/**
 * The angular momentum of a body whose principal moments were raised, from the angular momentum of its
 * particles. The particles' velocities about the centre of mass, v_i - V = omega x r_i, carry the
 * momentum l = sum_i m_i r_i x (v_i - V) = I omega, with I the moments of the particles' masses; the
 * body moves with the raised moments I' and the same angular velocity, so its momentum is
 * L = I' omega, in the principal frame L_k = s_k l_k with s_k = I'_k / I_k (1 on an axis of zero
 * moment). l (lab frame) is replaced by L; the attitude a takes the lab frame to the principal frame.
 * Where every s_k is 1 nothing is computed, so that bodies whose moments were not raised keep l bit
 * for bit.
 */
RIGID_FUNCTION void rigidRaiseAngularMomentum(double a[3][3], const double* scale, double* l) {
    double body[3];
    int i;
    if (!rigidMomentsRaised(scale))
        return;
    rigidMultiplyVector(a, l, body);
    for (i = 0; i < 3; i++)
        body[i] *= scale[i];
    for (i = 0; i < 3; i++)
        l[i] = a[0][i]*body[0] + a[1][i]*body[1] + a[2][i]*body[2];
}

/** The rotational kinetic energy sum_k L_k^2 / (2 I_k) of a body from its principal-frame angular momentum; a zero moment carries none. */
RIGID_FUNCTION double rigidRotationalEnergy(const double* moments, const double* angularMomentum) {
    double energy = 0.0;
    int k;
    for (k = 0; k < 3; k++)
        if (moments[k] > 0.0)
            energy += 0.5*angularMomentum[k]*angularMomentum[k]/moments[k];
    return energy;
}

/** The translational kinetic energy M V^2 / 2 of a mass with velocity V. */
RIGID_FUNCTION double rigidTranslationalEnergy(double mass, const double* velocity) {
    return 0.5*mass*(velocity[0]*velocity[0] + velocity[1]*velocity[1] + velocity[2]*velocity[2]);
}

#endif /* OPENMMRIGID_CORE_BASICS_H_ */
