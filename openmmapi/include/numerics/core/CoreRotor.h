/*
 * The numerics core, part 3: the exact motion of a free rigid rotor, R. van Zon and J. Schofield,
 * "Numerical implementation of the exact dynamics of free rigid bodies", J. Comput. Phys. 225 (2007)
 * 145-164 (cited below as vZS), as plain functions on fixed-size data. docs/free-rotor-notes.md
 * restates the algorithm step by step ("notes, initialization step 9") and lists its delicate cases.
 * See numerics/RigidCore.h for the rules every core file follows; numerics/FreeRotor.h is the
 * validating class around these functions.
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
 *     theta series: the complex theta function of vZS eqs. (3.54), (4.3)-(4.8). Its nome
 *       q = exp(-pi K'/K) tends to 1 at the separatrix (m -> 1), where the series stop converging.
 *     elliptic integral: eq. (3.20) rewritten as Omega = L/I3 + L (I3 - I1) / (I1 I3 (1 - n sn^2(u|m)))
 *       with n = -I3 (I2 - I1) / (I1 (I3 - I2)) <= 0, so that psi is an incomplete elliptic integral of
 *       the third kind (DLMF 19.2.7), evaluated with Carlson's RF and RJ. It is valid for every m in
 *       [0, 1], the separatrix m = 1 included.
 *   Both are exact to rounding wherever they are defined (checked down to 1 - m = 1e-24 for the
 *   series); the automatic choice takes the theta series, the cheaper one, for m <= 0.9999 (at most
 *   eight terms) and the elliptic integral above.
 *
 * Accuracy: omega and A to about 1e-14 relative for times of a few rotation periods; over long times
 * the phase error grows like (rotation angle) x machine epsilon, which is inherent in the rounding of t.
 * A body whose moments rigidClassifyMoments() snaps (equal to within 1e-13 of the largest) moves
 * exactly as the snapped body, which differs from the given one by at most that much.
 */
#ifndef OPENMMRIGID_CORE_ROTOR_H_
#define OPENMMRIGID_CORE_ROTOR_H_

/** The kinds of body. The first four are FreeRotor::Kind; a point has no rotation at all. */
enum RigidKind {
    RigidKindLinear = 0,
    RigidKindSpherical = 1,
    RigidKindSymmetric = 2,
    RigidKindAsymmetric = 3,
    RigidKindPoint = 4
};

/** How an asymmetric top evaluates its precession angle (FreeRotor::Representation). */
enum RigidRepresentation {
    RigidRepresentationAutomatic = 0,
    RigidRepresentationThetaSeries = 1,
    RigidRepresentationEllipticIntegral = 2
};

/*
 * The most terms of the theta series. q^{n^2} < eps/4 needs n^2 > ln(eps/4)/ln(q) with
 * ln(q) = -pi K'/K; K grows like ln(4/sqrt(1 - m)), so even 1 - m = 1e-300 needs only 52 terms,
 * and the automatic choice (m <= 0.9999) needs at most 8.
 */
enum { RigidMaxThetaTerms = 64 };

/** The automatic representation uses the theta series up to this elliptic parameter m. */
RIGID_FUNCTION double rigidAutomaticThetaSeriesLimit(void) {
    return 0.9999;
}

/** A body's principal moments as the dynamics uses them, with their kind. */
typedef struct {
    int kind;          /* a RigidKind */
    int uniqueAxis;    /* symmetric: the axis whose moment differs; linear: the zero axis; otherwise -1 */
    double moments[3]; /* the moments, with those found equal (or zero) made exactly so */
} RigidShape;

/** Moments that differ by at most this fraction of the largest are equal (see rigidClassifyMoments). */
RIGID_FUNCTION double rigidKindTolerance(void) {
    return 1e-13;
}

/**
 * The one classification of principal moments into kinds, for the rotor and for the body topology.
 *
 * Two moments are equal, and a moment is zero, when they differ by at most 1e-13 of the largest
 * moment; equal moments are then made exactly equal (a pair takes its mean, three take their median)
 * and a zero moment exactly zero, so that the formula of the kind is exact for the moments it returns.
 * Why 1e-13: moments computed from coordinates a few nm from the origin carry rounding of about
 * 1e-14 relative (the shape's coordinates are differences of positions of that size), which must not
 * make a symmetric molecule asymmetric; and moments that differ by 1e-12 relative are a genuine
 * asymmetric top that the general formulas (exact for any distinct moments, m -> 0 included) must
 * keep. Snapping changes a moment by at most 5e-14 relative, and the motion by at most that relative
 * amount per radian turned: below what any force field resolves, and never a systematic drift of
 * the conserved quantities, since the snapped moments are the body's moments from then on.
 *
 * @param moments  the three principal moments, in any order
 * @param shape    on exit (when the status is RigidStatusOk), the kind and the moments to use
 * @return RigidStatusOk; RigidStatusNegativeMoment for a negative or NaN moment;
 *         RigidStatusTwoZeroMoments when two moments are zero but not the third;
 *         RigidStatusUnequalLinear when one moment is zero and the other two are not equal.
 *         Three zero moments are a point (RigidKindPoint).
 */
RIGID_FUNCTION int rigidClassifyMoments(const double* moments, RigidShape* shape) {
    const double largest = rigidMax3(moments[0], moments[1], moments[2]);
    const double tolerance = rigidKindTolerance()*largest;
    int k, zeros = 0, zeroAxis = -1, equalPairs = 0, pairAxis = -1;
    for (k = 0; k < 3; k++) {
        if (!(moments[k] >= 0.0))
            return RigidStatusNegativeMoment;
        shape->moments[k] = moments[k];
    }
    shape->kind = RigidKindAsymmetric;
    shape->uniqueAxis = -1;
    for (k = 0; k < 3; k++)
        if (moments[k] <= tolerance) {
            zeros++;
            zeroAxis = k;
        }
    if (zeros == 3) {
        shape->kind = RigidKindPoint;
        for (k = 0; k < 3; k++)
            shape->moments[k] = 0.0;
        return RigidStatusOk;
    }
    if (zeros == 2)
        return RigidStatusTwoZeroMoments;
    if (zeros == 1) {
        const double a = moments[(zeroAxis + 1)%3], b = moments[(zeroAxis + 2)%3];
        if (!(fabs(a - b) <= tolerance))
            return RigidStatusUnequalLinear;
        shape->kind = RigidKindLinear;
        shape->uniqueAxis = zeroAxis;
        shape->moments[zeroAxis] = 0.0;
        shape->moments[(zeroAxis + 1)%3] = shape->moments[(zeroAxis + 2)%3] = 0.5*(a + b);
        return RigidStatusOk;
    }
    /* pairAxis: the axis left out of the (last) equal pair, the unique axis of a symmetric top */
    for (k = 0; k < 3; k++)
        if (fabs(moments[(k + 1)%3] - moments[(k + 2)%3]) <= tolerance) {
            equalPairs++;
            pairAxis = k;
        }
    if (equalPairs >= 2) {
        /* the median of the three */
        const double a = moments[0], b = moments[1], c = moments[2];
        const double median = (a < b ? (b < c ? b : (a < c ? c : a)) : (a < c ? a : (b < c ? c : b)));
        shape->kind = RigidKindSpherical;
        for (k = 0; k < 3; k++)
            shape->moments[k] = median;
    }
    else if (equalPairs == 1) {
        const int i = (pairAxis + 1)%3, j = (pairAxis + 2)%3;
        const double mean = 0.5*(moments[i] + moments[j]);
        shape->kind = RigidKindSymmetric;
        shape->uniqueAxis = pairAxis;
        shape->moments[i] = shape->moments[j] = mean;
    }
    return RigidStatusOk;
}

/** The theta-series values at one argument u (see rigidThetaSeries). */
typedef struct {
    double sn, cn, dn, re, im;
} RigidThetaValues;

/** A free rotor: its initial state and what its motion needs, computed once by rigidRotorInitialize. */
typedef struct {
    int kind, uniqueAxis;
    int steady;          /* omega along a principal axis (or zero): uniform rotation */
    int representation;  /* asymmetric, not steady: the RigidRepresentation used; otherwise automatic */
    double moments[3], omega0[3], attitude0[3][3];
    double energy;
    double symmetricPrecession;  /* symmetric top: omega_p = (1 - I_unique / I_perp) omega_unique (eq. (3.26)) */
    /* Asymmetric top, all in internal axes: v_internal[j] = axisSign[j] * v_given[axisOf[j]]. */
    int axisOf[3];
    double axisSign[3], internalMoments[3];
    /* The frequencies below, and |L|, are kept in units of frequencyScale, the power of two near
     * max |omega_k| (see rigidRotorScaleFrequency()), and the evolution scales the time instead:
     * neither their products nor the time's underflow or overflow for any finite omega. */
    double frequencyScale;
    double angularMomentum;  /* |L| */
    double w1m, w2m, w3m, wp, m, m1, quarterPeriod, epsilon;
    double b[3][3];          /* B = T1'(omega(0))^T Q A(0) */
    /* Theta series (vZS eqs. (4.3)-(4.8)): its coefficients are generated term by term from these. */
    int thetaTerms;
    double nome, thetaScale;                 /* q and pi / (2K) */
    double sinhX, coshX, sinh2X, cosh2X;     /* of x and 2x, x = pi eta / (2K) */
    double snScale, cnScale, dnScale;
    double cosPhase1, sinPhase1, phase2;     /* cos A1, sin A1 and A2 */
    /* Elliptic integral of the third kind. */
    double characteristic;      /* n */
    double halfPeriodExcess;    /* Pi(n|m) - K, the growth of the excess over a half period 2K of u */
    double integralPrefactor;   /* L (I3 - I1) / (I1 I3 wp) */
    double integralAtStart;     /* the excess at u = epsilon */
} RigidRotor;

/**
 * The theta series at count = 1 or 2 arguments u[j], each from one sine and cosine of
 * zeta = pi u / 2K: the Jacobi functions sn, cn, dn (DLMF 22.2.4-22.2.6 with the theta functions of
 * DLMF 20.2.1-20.2.4) and the real and imaginary parts of theta_1 at pi (u - i eta) / 2K (vZS eq. (4.4)),
 * up to a common positive factor. The coefficients (notes, initialization step 9) are generated term
 * by term: q^{n(n+1)} and q^{n^2} by their ratios, cosh and sinh of (2n+1)x by the addition theorem.
 * The sums for A2 come out of the same pass: derivative = sum (2n+1) cr_n and value = -sum ci_n
 * (see rigidThetaInitialize). The argument sums run side by side, so that their multiplications overlap.
 */
RIGID_HOT_FUNCTION void rigidThetaSeries(const RigidRotor* r, int count, const double* u, RigidThetaValues* values,
                                         double* derivative, double* value) {
    /* sin and cos of k zeta for odd k (so, co) and even k (se, ce), each advanced by 2 zeta: two
     * independent recurrences for each argument. */
    double so[2], co[2], se[2], ce[2], s2[2], c2[2];
    double theta1[2], theta2[2], theta3[2], theta4[2], re[2], im[2];
    const double nome2 = r->nome*r->nome;
    double oddPower = 1.0, oddStep = nome2;     /* q^{n(n+1)} and q^{2(n+1)} */
    double evenPower = 1.0, evenStep = r->nome; /* q^{n^2} and q^{2n+1} */
    double sinhK = r->sinhX, coshK = r->coshX;  /* of (2n+1)x */
    double cr = 2.0*oddPower*coshK, ci = -2.0*oddPower*sinhK;
    int j, n;
    *derivative = 0.0 + cr;
    *value = 0.0 - ci;
    for (j = 0; j < count; j++) {
        const double zeta = r->thetaScale*u[j];
        rigidSinCos(zeta, &so[j], &co[j]);
        s2[j] = se[j] = 2.0*so[j]*co[j];
        c2[j] = ce[j] = (co[j] - so[j])*(co[j] + so[j]);
        theta1[j] = oddPower*so[j];
        theta2[j] = oddPower*co[j];
        theta3[j] = theta4[j] = 1.0;
        re[j] = cr*so[j];
        im[j] = ci*co[j];
    }
    for (n = 1; n < r->thetaTerms; n++) {
        const double sign = (n%2 == 0 ? 2.0 : -2.0);
        double even, signedEven, signedOdd, nextSinh;
        oddPower *= oddStep;
        oddStep *= nome2;
        evenPower *= evenStep;
        evenStep *= nome2;
        nextSinh = sinhK*r->cosh2X + coshK*r->sinh2X;
        coshK = coshK*r->cosh2X + sinhK*r->sinh2X;
        sinhK = nextSinh;
        /* cr = 2 (-1)^n q^{n(n+1)} cosh((2n+1)x), ci = -2 (-1)^n q^{n(n+1)} sinh((2n+1)x) */
        cr = sign*oddPower*coshK;
        ci = -sign*oddPower*sinhK;
        *derivative += (2*n + 1)*cr;
        *value -= ci;
        signedOdd = (n%2 == 0 ? oddPower : -oddPower);
        even = 2.0*evenPower;
        signedEven = (n%2 == 0 ? even : -even);
        for (j = 0; j < count; j++) {
            double nextOdd = so[j]*c2[j] + co[j]*s2[j], nextEven;
            co[j] = co[j]*c2[j] - so[j]*s2[j];
            so[j] = nextOdd;
            /* k = 2n */
            theta3[j] += even*ce[j];
            theta4[j] += signedEven*ce[j];
            /* k = 2n + 1 */
            re[j] += cr*so[j];
            im[j] += ci*co[j];
            theta1[j] += signedOdd*so[j];
            theta2[j] += oddPower*co[j];
            nextEven = se[j]*c2[j] + ce[j]*s2[j];
            ce[j] = ce[j]*c2[j] - se[j]*s2[j];
            se[j] = nextEven;
        }
    }
    for (j = 0; j < count; j++) {
        values[j].sn = r->snScale*theta1[j]/theta4[j];
        values[j].cn = r->cnScale*theta2[j]/theta4[j];
        values[j].dn = r->dnScale*theta3[j]/theta4[j];
        values[j].re = re[j];
        values[j].im = im[j];
    }
}

/**
 * T1'(omega) of vZS eq. (3.13) from L = (l1, l2, l3) in the internal body frame and |L|: its columns
 * are e1, e2 and L/|L|.
 */
RIGID_HOT_FUNCTION void rigidInvariantFrame(double l1, double l2, double l3, double angularMomentum, double t1[3][3]) {
    const double perp = sqrt(l1*l1 + l2*l2);
    const double inverseL = 1.0/angularMomentum, inversePerp = 1.0/perp, l3Ratio = l3*inverseL*inversePerp;
    t1[0][0] = l1*l3Ratio;
    t1[0][1] = -l2*inversePerp;
    t1[0][2] = l1*inverseL;
    t1[1][0] = l2*l3Ratio;
    t1[1][1] = l1*inversePerp;
    t1[1][2] = l2*inverseL;
    t1[2][0] = -perp*inverseL;
    t1[2][1] = 0.0;
    t1[2][2] = l3*inverseL;
}

/** T1'(omega) of vZS eq. (3.13) at u with the given sn, cn, dn: its columns are e1, e2 and L/|L| in the internal body frame. */
RIGID_HOT_FUNCTION void rigidBodyToInvariantFrame(const RigidRotor* r, double sn, double cn, double dn, double t1[3][3]) {
    /* L = (I1 w1m cn, I2 w2m sn, I3 w3m dn) (vZS eqs. (3.33)-(3.35)), in units of frequencyScale. */
    rigidInvariantFrame(r->internalMoments[0]*r->w1m*cn, r->internalMoments[1]*r->w2m*sn, r->internalMoments[2]*r->w3m*dn,
                        r->angularMomentum, t1);
}

/**
 * The attitude in internal axes, T1' T2' B, from T1' (rigidInvariantFrame), cos and sin of psi and B
 * (B row by row in b; notes, evolution step 3); rigidRotorCompose() takes it back to the given axes.
 */
RIGID_HOT_FUNCTION void rigidComposeInternal(double t1[3][3], double cosPsi, double sinPsi, const double* b,
                                             double internal[3][3]) {
    double rotation[3][3];
    int i, c;
    /* T1' T2' with T2' = [[cos, sin, 0], [-sin, cos, 0], [0, 0, 1]] (vZS eq. (3.14)). */
    for (i = 0; i < 3; i++) {
        rotation[i][0] = t1[i][0]*cosPsi - t1[i][1]*sinPsi;
        rotation[i][1] = t1[i][0]*sinPsi + t1[i][1]*cosPsi;
        rotation[i][2] = t1[i][2];
    }
    for (i = 0; i < 3; i++)
        for (c = 0; c < 3; c++)
            internal[i][c] = rotation[i][0]*b[c] + rotation[i][1]*b[3 + c] + rotation[i][2]*b[6 + c];
}

/**
 * The state of an asymmetric top once sn, cn, dn at u = wp t + eps and cos psi, sin psi are known:
 * omega from vZS eqs. (3.33)-(3.35), A = Q^T T1'(omega(t)) T2'(psi) B (notes, evolution step 3).
 */
RIGID_FUNCTION void rigidRotorCompose(const RigidRotor* r, double sn, double cn, double dn, double cosPsi, double sinPsi,
                                      double* omega, double attitude[3][3]) {
    double t1[3][3], internal[3][3], w[3];
    int j, c;
    w[0] = r->w1m*cn*r->frequencyScale;
    w[1] = r->w2m*sn*r->frequencyScale;
    w[2] = r->w3m*dn*r->frequencyScale;
    rigidBodyToInvariantFrame(r, sn, cn, dn, t1);
    rigidComposeInternal(t1, cosPsi, sinPsi, &r->b[0][0], internal);
    /* A = Q^T (T1' T2' B) */
    for (j = 0; j < 3; j++) {
        omega[r->axisOf[j]] = r->axisSign[j]*w[j];
        for (c = 0; c < 3; c++)
            attitude[r->axisOf[j]][c] = r->axisSign[j]*internal[j][c];
    }
}

/**
 * cos and sin of the precession angle psi = A1 + A2 t - arg theta_1(u) (vZS eq. (4.3); notes,
 * evolution step 2) from cos A1, sin A1, cos and sin of A2 t, and theta_1(u) = re + i im up to a
 * positive factor: the angle sums done on cosines and sines.
 */
RIGID_HOT_FUNCTION void rigidPrecessionAngle(double cosPhase1, double sinPhase1, double c2, double s2, double re, double im,
                                             double* cosPsi, double* sinPsi) {
    const double size = sqrt(re*re + im*im);
    const double c = cosPhase1*c2 - sinPhase1*s2, s = sinPhase1*c2 + cosPhase1*s2;  /* of A1 + A2 t */
    *cosPsi = (c*re + s*im)/size;
    *sinPsi = (s*re - c*im)/size;
}

/** cos and sin of the precession angle psi from theta_1 at the time t (in units of 1/frequencyScale; vZS eq. (4.3)). */
RIGID_FUNCTION void rigidThetaPrecession(const RigidRotor* r, double t, const RigidThetaValues* value, double* cosPsi,
                                         double* sinPsi) {
    double c2, s2;
    rigidSinCos(r->phase2*t, &s2, &c2);
    rigidPrecessionAngle(r->cosPhase1, r->sinPhase1, c2, s2, value->re, value->im, cosPsi, sinPsi);
}

/**
 * The part of int_0^u du' / (1 - n sn^2(u')) beyond u itself, for any real u. Since the
 * RF term of Pi(n; am(u)|m) is exactly u on [-K, K] (DLMF 19.25.5), only the RJ term remains:
 * reduce u = 2K j + r with |r| <= K; the excess is 2 j (n/3) RJ(0, m1, 1, 1 - n) plus
 * (n/3) sn^3(r) RJ(cn^2, dn^2, 1, 1 - n sn^2) (DLMF 19.25.14), and sn(r) = (-1)^j sn(u).
 * On the separatrix (m = 1, K infinite) the integral is elementary: with nu = -n,
 * int_0^u du' / (1 + nu tanh^2 u') = (u + sqrt(nu) atan(sqrt(nu) tanh u)) / (1 + nu).
 */
RIGID_FUNCTION double rigidPrecessionAngleExcess(const RigidRotor* r, double u, const RigidJacobi* f) {
    const double n = r->characteristic;
    double halfPeriods, s;
    if (r->m1 == 0.0) {
        const double nu = -n, root = sqrt(nu);
        return (root*atan(root*f->sn) - nu*u)/(1.0 + nu);
    }
    halfPeriods = rint(u/(2.0*r->quarterPeriod));
    s = (fmod(halfPeriods, 2.0) == 0.0 ? f->sn : -f->sn);
    return 2.0*halfPeriods*r->halfPeriodExcess + n/3.0*s*s*s*rigidCarlsonRJ(f->cn*f->cn, f->dn*f->dn, 1.0, 1.0 - n*s*s);
}

/**
 * The power of two 2^e with x = f 2^e, 1/2 <= f < 1 (frexp's split), and its inverse, for x > 0.
 * From the exponent field E of x = 1.f 2^(E - 1023): 2^e has field E + 1 and 2^-e field 2045 - E, both
 * normal numbers unless x is subnormal or within a factor 4 of the largest double, where frexp and
 * ldexp take over (for omega above 2^1023 the scale overflows; such an omega has no finite energy
 * anyway). rigidDoubleBits and rigidBitsDouble are the prelude's bit casts.
 */
RIGID_HOT_FUNCTION void rigidPowerOfTwoAbove(double x, double* scale, double* inverseScale) {
    const RigidUInt64 field = rigidDoubleBits(x) >> 52;
    if (field == 0 || field >= 2045) {
        int exponent;
        (void) frexp(x, &exponent);
        *scale = ldexp(1.0, exponent);
        *inverseScale = ldexp(1.0, -exponent);
        return;
    }
    *scale = rigidBitsDouble((field + 1) << 52);
    *inverseScale = rigidBitsDouble((2045 - field) << 52);
}

/**
 * Initialization, first part: omega / 2^e with 2^e near max|omega_k|, so that no square underflows
 * or overflows and the division is exact; the quantities with units of frequency are scaled back
 * at the end. A subnormal omega is first multiplied by 2^600, so that 1/2^e is a double too.
 * Returns 2^e.
 */
RIGID_HOT_FUNCTION double rigidRotorScaleFrequency(const double* omega, double* scaledOmega) {
    const double largest = rigidMax3(fabs(omega[0]), fabs(omega[1]), fabs(omega[2]));
    const double prescale = (largest < 0x1p-1022 ? 0x1p600 : 1.0);
    double scale, inverseScale;
    int k;
    rigidPowerOfTwoAbove(largest*prescale, &scale, &inverseScale);
    for (k = 0; k < 3; k++)
        scaledOmega[k] = omega[k]*prescale*inverseScale;
    return scale/prescale;
}

/**
 * Initialization, second part: the internal axes. Put the middle moment on the second axis by a
 * cyclic (proper) permutation, then apply the Jacobi ordering of vZS eq. (3.32) (notes,
 * initialization step 2): if needed, swap axes 1 and 3 and flip axis 2 (vZS eq. (4.10)).
 * Sets axisOf, axisSign and internalMoments, and w0, the scaled omega in internal axes.
 */
RIGID_HOT_FUNCTION void rigidRotorOrderAxes(RigidRotor* r, const double* scaledOmega, double* w0) {
    const double* moments = r->moments;
    int middle = 0, k, j, cyclic[3];
    double ix, iy, iz, twoEIyMinusL2 = 0.0;
    int flip;
    for (k = 0; k < 3; k++) {
        const int below = (moments[(k + 1)%3] < moments[k]) + (moments[(k + 2)%3] < moments[k]);
        if (below == 1)
            middle = k;
    }
    cyclic[0] = (middle + 2)%3;
    cyclic[1] = middle;
    cyclic[2] = (middle + 1)%3;
    ix = moments[cyclic[0]];
    iy = moments[cyclic[1]];
    iz = moments[cyclic[2]];
    /* 2E Iy - L^2 = sum_k I_k w_k^2 (Iy - I_k), free of the cancellation of the difference. */
    for (k = 0; k < 3; k++)
        twoEIyMinusL2 += moments[k]*scaledOmega[k]*scaledOmega[k]*(iy - moments[k]);
    flip = (twoEIyMinusL2 > 0.0 && ix < iz) || (twoEIyMinusL2 < 0.0 && ix > iz);
    for (j = 0; j < 3; j++) {
        r->axisOf[j] = (flip ? cyclic[2 - j] : cyclic[j]);
        r->axisSign[j] = (flip && j == 1 ? -1.0 : 1.0);
        r->internalMoments[j] = moments[r->axisOf[j]];
        w0[j] = r->axisSign[j]*scaledOmega[r->axisOf[j]];
    }
}

/** What rigidInvariantsOf() finds, in units of the frequency scale: |L|, the amplitudes, wp, m and 1 - m. */
typedef struct {
    double angularMomentum, w1m, w2m, w3m, wp, m, m1;
} RigidInvariants;

/**
 * Initialization, third part: the invariants and the parameter (notes, initialization steps 1 and 5;
 * vZS eqs. (3.36)-(3.41)) from the internal moments and the internal, scaled w0, into v. Returns 0 when L lies along axis 3 to within
 * the range of doubles: the precession amplitude is then below 1e-300 |omega|, and the uniform
 * rotation is exact to that level.
 */
RIGID_HOT_FUNCTION int rigidInvariantsOf(const double* moments, const double* w0, RigidInvariants* v) {
    const double i1 = moments[0], i2 = moments[1], i3 = moments[2];
    double l2MinusTwoEI1 = 0.0, l2MinusTwoEI2 = 0.0, l2MinusTwoEI3 = 0.0, l2 = 0.0;
    double sign1, sign3, numerator, denominator;
    int k;
    /* L^2 - 2E I_j = sum_k I_k w_k^2 (I_k - I_j) (notes: "Where the formulas are delicate"). */
    for (k = 0; k < 3; k++) {
        const double weight = moments[k]*w0[k]*w0[k];
        l2MinusTwoEI1 += weight*(moments[k] - i1);
        l2MinusTwoEI3 += weight*(moments[k] - i3);
        l2 += weight*moments[k];
    }
    v->angularMomentum = sqrt(l2);
    /* sgn(0) is taken as +1; any fixed choice satisfies Euler's equations. */
    sign1 = (w0[0] < 0.0 ? -1.0 : 1.0);
    sign3 = (w0[2] < 0.0 ? -1.0 : 1.0);
    v->w1m = sign1*sqrt(rigidPositivePart(l2MinusTwoEI3/(i1*(i1 - i3))));
    v->w2m = -sign1*sqrt(rigidPositivePart(l2MinusTwoEI3/(i2*(i2 - i3))));
    v->w3m = sign3*sqrt(rigidPositivePart(l2MinusTwoEI1/(i3*(i3 - i1))));
    v->wp = (i2 > i3 ? 1.0 : -1.0)*sign3*sqrt(rigidPositivePart(l2MinusTwoEI1*(i3 - i2)/(i1*i2*i3)));
    numerator = l2MinusTwoEI3*(i1 - i2);
    denominator = l2MinusTwoEI1*(i3 - i2);
    v->m = rigidClamp(numerator/denominator, 0.0, 1.0);
    /* 1 - m = (L^2 - 2E I2)(I3 - I1) / ((L^2 - 2E I1)(I3 - I2)), again without cancellation. */
    for (k = 0; k < 3; k++)
        l2MinusTwoEI2 += moments[k]*w0[k]*w0[k]*(moments[k] - i2);
    v->m1 = rigidClamp(l2MinusTwoEI2*(i3 - i1)/denominator, 0.0, 1.0);
    if (!(v->m > 0.0) || v->w1m == 0.0) {
        v->m = 0.0;
        return 0;
    }
    return 1;
}

/** The invariants v, from rigidInvariantsOf(), into the rotor. */
RIGID_HOT_FUNCTION void rigidRotorTakeInvariants(RigidRotor* r, const RigidInvariants* v) {
    r->angularMomentum = v->angularMomentum;
    r->w1m = v->w1m;
    r->w2m = v->w2m;
    r->w3m = v->w3m;
    r->wp = v->wp;
    r->m = v->m;
    r->m1 = v->m1;
}

/**
 * Initialization, fourth part: the initial argument. sn(eps) = w2/w2m, cn(eps) = w1/w1m,
 * dn(eps) = w3/w3m (vZS eq. (3.42); notes, initialization step 6), with all three ratios used so that
 * eps keeps full precision near the turning points (the clamps absorb rounding beyond 1). Returns 0
 * when omega lies along the middle axis to within the range of doubles: the unstable steady rotation.
 */
RIGID_HOT_FUNCTION int rigidInitialArgumentOf(const RigidInvariants* v, const double* w0, RigidJacobi* f) {
    f->sn = rigidClamp(w0[1]/v->w2m, -1.0, 1.0);
    f->cn = rigidClamp(w0[0]/v->w1m, 0.0, 1.0);
    f->dn = rigidClamp(w0[2]/v->w3m, 0.0, 1.0);
    return !(f->cn*f->cn == 0.0 && f->dn*f->dn == 0.0);
}

/**
 * Jacobi's nome series q = l + 2 l^5 + 15 l^9 + 150 l^13 + ... with l = (1 - p^(1/4)) / (2 (1 + p^(1/4)))
 * (Abramowitz & Stegun 17.3.21) for the complementary parameter p, given p^(1/4) and 1 - p;
 * 1 - p^(1/4) = (1 - p) / ((1 + p^(1/2))(1 + p^(1/4))) is free of cancellation for p near 1.
 */
RIGID_FUNCTION double rigidJacobiNome(double fourthRoot, double oneMinusParameter) {
    const double l = oneMinusParameter/((1.0 + fourthRoot*fourthRoot)*(1.0 + fourthRoot))/(2.0*(1.0 + fourthRoot));
    const double l4 = l*l*l*l;
    return l*(1.0 + l4*(2.0 + l4*(15.0 + l4*(150.0 + l4*(1707.0 + l4*(20910.0 + l4*268616.0))))));
}

/**
 * Theta-series coefficients, first part: the nome, the number of terms, K and the scales of the
 * Jacobi functions. The nome converges fast for m <= 1/2 (l <= 0.044); above, the same series in m
 * gives the complementary nome q' = exp(-pi K/K'), and ln q ln q' = pi^2. Then K = (pi/2) theta_3(0|q)^2
 * (DLMF 20.9.2): no AGM is needed. The powers q^{n(n+1)} and q^{n^2} give theta_2, theta_3, theta_4 at
 * zero (DLMF 20.2.2-20.2.4; theta_2 without its factor 2 q^{1/4}, which rigidThetaSeries() drops from
 * theta_1 as well), summed until q^{n^2} < eps/4. The theta_1 coefficients fall at least as fast
 * relative to their first term: |eta| <= K' makes |x| <= pi K' / 2K = -ln(q) / 2, so
 * q^{n(n+1)} e^{2n|x|} <= q^{n^2}. The same terms therefore serve every series.
 * Returns RigidStatusThetaNotConverged if RigidMaxThetaTerms do not suffice.
 */
RIGID_HOT_FUNCTION int rigidThetaConstants(RigidRotor* r) {
    const double m = r->m, m1 = r->m1;
    double theta2 = 0.0, theta3 = 1.0, theta4 = 1.0;
    double oddPower = 1.0, oddStep, evenPower = 1.0, evenStep;  /* q^{n(n+1)}, q^{2(n+1)}, q^{n^2}, q^{2n+1} */
    int n, converged = 0;
    r->nome = (m <= 0.5 ? rigidJacobiNome(sqrt(sqrt(m1)), m) :
            exp(rigidPi()*rigidPi()/log(rigidJacobiNome(sqrt(sqrt(m)), m1))));
    oddStep = r->nome*r->nome;
    evenStep = r->nome;
    for (n = 0; n < RigidMaxThetaTerms; n++) {
        theta2 += oddPower;
        if (n > 0) {
            theta3 += 2.0*evenPower;
            theta4 += (n%2 == 0 ? 2.0 : -2.0)*evenPower;
        }
        r->thetaTerms = n + 1;
        if (n > 0 && evenPower < 0.25*rigidEpsilon()) {
            converged = 1;
            break;
        }
        oddPower *= oddStep;
        oddStep *= r->nome*r->nome;
        evenPower *= evenStep;
        evenStep *= r->nome*r->nome;
    }
    if (!converged)
        return RigidStatusThetaNotConverged;
    /* K = (pi/2) theta_3(0|q)^2 (DLMF 20.9.2) */
    r->quarterPeriod = 0.5*rigidPi()*theta3*theta3;
    r->thetaScale = rigidPi()/(2.0*r->quarterPeriod);
    /* The Jacobi functions' scales (DLMF 22.2.4-22.2.6). */
    r->snScale = theta3/theta2;
    r->cnScale = theta4/theta2;
    r->dnScale = theta4/theta3;
    return RigidStatusOk;
}

/**
 * Theta-series coefficients, second part: eta and the initial argument eps, then x = pi eta / 2K.
 * eta = sgn(w3m) K' - F(I3 w3m / L | 1 - m) (vZS eq. (3.47); notes, initialization step 7). With
 * x = I3 w3m / L the difference K' - F(|x| | m1) is F of the complementary amplitude (DLMF 19.11.3),
 * which by the homogeneity of RF is sqrt(c) RF(m L3^2, m L^2, m L3^2 + c) with L3 = I3 w3m and
 * c = L^2 - L3^2 = (I1 w1m)^2 (at u = 0, where omega = (w1m, 0, w3m)). This form has no cancellation
 * when L is near axis 3. The same call gives eps = sn0 RF(cn0^2, dn0^2, 1) (DLMF 19.25.5), the two
 * integrals side by side. The hyperbolic functions of x are taken from expm1, so that sinh keeps its
 * relative accuracy when x is small (L near axis 3).
 */
RIGID_HOT_FUNCTION void rigidThetaPhase(RigidRotor* r, const RigidJacobi* f0) {
    const double m = r->m, i1 = r->internalMoments[0], i3 = r->internalMoments[2];
    const double l3 = i3*r->w3m, c = (i1*r->w1m)*(i1*r->w1m);
    double rx[2], ry[2], rz[2], rf[2], eta, x, expm1x;
    rx[0] = m*l3*l3;
    rx[1] = f0->cn*f0->cn;
    ry[0] = m*r->angularMomentum*r->angularMomentum;
    ry[1] = f0->dn*f0->dn;
    rz[0] = m*l3*l3 + c;
    rz[1] = 1.0;
    rigidCarlsonRFLockstep(2, rx, ry, rz, rf);
    eta = (r->w3m < 0.0 ? -1.0 : 1.0)*sqrt(c)*rf[0];
    r->epsilon = f0->sn*rf[1];
    x = r->thetaScale*eta;
    expm1x = expm1(x);
    r->sinhX = 0.5*expm1x*(1.0 + 1.0/(1.0 + expm1x));
    r->coshX = sqrt(1.0 + r->sinhX*r->sinhX);
    r->sinh2X = 2.0*r->sinhX*r->coshX;
    r->cosh2X = 1.0 + 2.0*r->sinhX*r->sinhX;
}

/**
 * A2 and A1 of the theta-series representation (as cos A1 and sin A1) from the series at u = eps:
 * the sums derivative and value of rigidThetaSeries, and theta_1(eps) = re + i im up to a positive factor.
 */
RIGID_HOT_FUNCTION void rigidThetaAngles(double angularMomentum, double i1, double thetaScale, double wp, double derivative,
                                         double value, double re, double im, double* phase2, double* cosPhase1,
                                         double* sinPhase1) {
    /* A2 (vZS eq. (3.53), (4.8); notes, initialization step 8): L/I1 + (pi wp / 2K) times the bracket
     * [coth(x) - 2 sum q^{2n}/(1 - q^{2n}) (xi^n - xi^-n)], which is i theta_1'/theta_1 at i x
     * (DLMF 20.5.10). Written with the theta series itself it is sum (2n+1) cr / (-sum ci): the same
     * few terms instead of a Lambert series in q. */
    const double size = sqrt(re*re + im*im);
    *phase2 = angularMomentum/i1 + thetaScale*wp*derivative/value;
    /* A1 = arg theta_1(eps) (vZS eq. (4.5); notes, initialization step 10); only its cosine and sine are needed. */
    *cosPhase1 = re/size;
    *sinPhase1 = im/size;
}

/**
 * Theta-series coefficients, last part, from the series at u = eps (values, and the sums derivative
 * and value of rigidThetaSeries): A2, A1 (rigidThetaAngles), and f0 becomes sn, cn, dn at eps.
 */
RIGID_HOT_FUNCTION void rigidThetaFinish(RigidRotor* r, const RigidThetaValues* values, double derivative, double value,
                                         RigidJacobi* f0) {
    rigidThetaAngles(r->angularMomentum, r->internalMoments[0], r->thetaScale, r->wp, derivative, value, values->re,
                     values->im, &r->phase2, &r->cosPhase1, &r->sinPhase1);
    f0->sn = values->sn;
    f0->cn = values->cn;
    f0->dn = values->dn;
}

/**
 * The theta-series representation (vZS Section 4.1): its coefficients, A1 and A2, and the Jacobi
 * functions at eps in f0. With fused, the series is also evaluated at the scaled time
 * scaledTime, into *fusedValue, in the same pass. The coefficients drop their common factor q^{1/4},
 * since only the phase of theta_1 enters psi (notes, initialization step 9).
 */
RIGID_HOT_FUNCTION int rigidThetaInitialize(RigidRotor* r, RigidJacobi* f0, int fused, double scaledTime,
                                        RigidThetaValues* fusedValue) {
    double arguments[2], derivative, value;
    RigidThetaValues values[2];
    const int status = rigidThetaConstants(r);
    if (status != RigidStatusOk)
        return status;
    rigidThetaPhase(r, f0);
    arguments[0] = r->epsilon;
    arguments[1] = r->wp*scaledTime + r->epsilon;
    /* the argument count a constant at each call, so that the inlined series is unrolled for it */
    if (fused) {
        rigidThetaSeries(r, 2, arguments, values, &derivative, &value);
        *fusedValue = values[1];
    }
    else
        rigidThetaSeries(r, 1, arguments, values, &derivative, &value);
    rigidThetaFinish(r, &values[0], derivative, value, f0);
    return RigidStatusOk;
}

/**
 * The elliptic-integral representation: K, eps = F(sn0 | m) (vZS eq. (3.42)), the characteristic n
 * and the excess of the third-kind integral at eps; f0 becomes sn, cn, dn at eps.
 */
RIGID_FUNCTION void rigidEllipticIntegralInitialize(RigidRotor* r, RigidJacobi* f0) {
    const double i1 = r->internalMoments[0], i2 = r->internalMoments[1], i3 = r->internalMoments[2];
    r->quarterPeriod = rigidEllipticK(r->m1);
    /* F from the Jacobi functions of its value (DLMF 19.25.5 with sin(phi) = sn, cos^2 = cn^2, Delta^2 = dn^2) */
    r->epsilon = f0->sn*rigidCarlsonRF(f0->cn*f0->cn, f0->dn*f0->dn, 1.0);
    r->characteristic = -i3*(i2 - i1)/(i1*(i3 - i2));
    r->integralPrefactor = r->angularMomentum*(i3 - i1)/(i1*i3*r->wp);
    /* The excess of Pi(n|m) over K over a half period: (n/3) RJ(0, m1, 1, 1 - n) (DLMF 19.25.2 with DLMF 19.25.14). */
    r->halfPeriodExcess = (r->m1 == 0.0 ? 0.0 : r->characteristic/3.0*rigidCarlsonRJ(0.0, r->m1, 1.0, 1.0 - r->characteristic));
    rigidJacobiElliptic(r->epsilon, r->m, r->m1, f0);
    r->integralAtStart = rigidPrecessionAngleExcess(r, r->epsilon, f0);
}

/**
 * Initialization of an asymmetric top, the part before the representation: scaling, axis ordering,
 * invariants and parameter, and sn, cn, dn of the initial argument in f0. Returns 0 (and marks the
 * rotor steady) when omega lies along a principal axis to within the range of doubles; *scale is
 * the frequency scale 2^e.
 */
RIGID_HOT_FUNCTION int rigidRotorAsymmetricStart(RigidRotor* r, double* scale, RigidJacobi* f0) {
    double scaledOmega[3], w0[3];
    RigidInvariants v;
    int moving;
    *scale = rigidRotorScaleFrequency(r->omega0, scaledOmega);
    rigidRotorOrderAxes(r, scaledOmega, w0);
    moving = rigidInvariantsOf(r->internalMoments, w0, &v) && rigidInitialArgumentOf(&v, w0, f0);
    rigidRotorTakeInvariants(r, &v);
    if (!moving)
        r->steady = 1;
    return moving;
}

/**
 * Initialization of an asymmetric top, the part after the representation: B = T1'(omega(0))^T Q A(0)
 * (notes, initialization step 4) from sn, cn, dn at u = eps as the representation evaluated them,
 * and the frequency scale.
 */
RIGID_HOT_FUNCTION void rigidRotorAsymmetricFinish(RigidRotor* r, const RigidJacobi* f0, double scale) {
    double qa[3][3], t1[3][3], b[3][3];
    int j, c;
    for (j = 0; j < 3; j++)
        for (c = 0; c < 3; c++)
            qa[j][c] = r->axisSign[j]*r->attitude0[r->axisOf[j]][c];
    rigidBodyToInvariantFrame(r, f0->sn, f0->cn, f0->dn, t1);
    rigidMultiplyTransposed(t1, qa, b);
    for (j = 0; j < 3; j++)
        for (c = 0; c < 3; c++)
            r->b[j][c] = b[j][c];
    r->frequencyScale = scale;
}

/**
 * Initialization of an asymmetric top that is not known to be steady: scaling, axis ordering,
 * invariants and parameter, initial argument, then the coefficients of the representation and
 * B = T1'(omega(0))^T Q A(0) (notes, initialization step 4). Each representation evaluates sn, cn, dn
 * at u = eps in its own way; building B from those values (rather than from the given omega) makes
 * the evolution to t = 0 return A(0) to rounding. With fused, the theta series is also evaluated at
 * time t into *fusedValue (see rigidRotorAdvance).
 */
RIGID_FUNCTION int rigidRotorInitializeAsymmetric(RigidRotor* r, int requested, int fused, double t,
                                                  RigidThetaValues* fusedValue) {
    RigidJacobi f0;
    double scale;
    if (!rigidRotorAsymmetricStart(r, &scale, &f0))
        return RigidStatusOk;
    if (requested == RigidRepresentationAutomatic)
        requested = (r->m <= rigidAutomaticThetaSeriesLimit() ? RigidRepresentationThetaSeries :
                     RigidRepresentationEllipticIntegral);
    if (requested == RigidRepresentationThetaSeries && r->m1 == 0.0)
        return RigidStatusThetaOnSeparatrix;
    r->representation = requested;
    if (requested == RigidRepresentationThetaSeries) {
        /* the time in the unit of the scaled frequencies (exact: scale is a power of two) */
        const int status = rigidThetaInitialize(r, &f0, fused, (fused ? t*scale : 0.0), fusedValue);
        if (status != RigidStatusOk)
            return status;
    }
    else
        rigidEllipticIntegralInitialize(r, &f0);
    rigidRotorAsymmetricFinish(r, &f0, scale);
    return RigidStatusOk;
}

/**
 * Initialization, common part: the kind, moments, initial state and energy, the steady rotations and
 * the symmetric top's precession (see rigidRotorInitialize). Returns 1 for an asymmetric top that is
 * not known to be steady, which rigidRotorInitializeAsymmetric() must then complete.
 */
RIGID_HOT_FUNCTION int rigidRotorSetUp(RigidRotor* r, const RigidShape* shape, const double* omega, double attitude[3][3]) {
    int k, j, zeroComponents = 0;
    r->kind = shape->kind;
    r->uniqueAxis = (shape->kind == RigidKindSymmetric ? shape->uniqueAxis : -1);
    r->representation = RigidRepresentationAutomatic;
    r->steady = 0;
    r->symmetricPrecession = 0.0;
    r->m = 0.0;
    r->frequencyScale = 1.0;
    for (k = 0; k < 3; k++) {
        r->moments[k] = shape->moments[k];
        /* no rotation about a zero moment's axis (a linear body's, or a point's) */
        r->omega0[k] = ((shape->kind == RigidKindLinear || shape->kind == RigidKindPoint) && shape->moments[k] == 0.0 ?
                        0.0 : omega[k]);
        zeroComponents += (r->omega0[k] == 0.0);
    }
    for (k = 0; k < 3; k++)
        for (j = 0; j < 3; j++)
            r->attitude0[k][j] = attitude[k][j];
    r->energy = 0.5*(r->moments[0]*r->omega0[0]*r->omega0[0] + r->moments[1]*r->omega0[1]*r->omega0[1] +
                     r->moments[2]*r->omega0[2]*r->omega0[2]);
    r->steady = (zeroComponents >= 2 || r->kind == RigidKindSpherical || r->kind == RigidKindLinear ||
                 r->kind == RigidKindPoint);
    if (r->kind == RigidKindSymmetric)
        r->symmetricPrecession = (1.0 - r->moments[r->uniqueAxis]/r->moments[(r->uniqueAxis + 1)%3])*r->omega0[r->uniqueAxis];
    return r->kind == RigidKindAsymmetric && !r->steady;
}

/**
 * Build the rotor of a body from its initial state. Contract: shape from rigidClassifyMoments(),
 * omega and attitude finite, attitude orthonormal with determinant +1. For a linear body the
 * component of omega along its axis is dropped; a point does not turn (its omega becomes zero). With fused, an asymmetric top that
 * uses the theta series also evaluates the series at time t into *fusedValue (rigidRotorAdvance).
 *
 * @param requested  a RigidRepresentation
 * @return RigidStatusOk; RigidStatusUnknownRepresentation; RigidStatusThetaOnSeparatrix when the theta
 *         series is requested at m = 1; RigidStatusThetaNotConverged when it would need more than
 *         RigidMaxThetaTerms terms (never for the automatic choice).
 */
RIGID_FUNCTION int rigidRotorInitialize(RigidRotor* r, const RigidShape* shape, const double* omega, double attitude[3][3],
                                        int requested, int fused, double t, RigidThetaValues* fusedValue) {
    if (requested != RigidRepresentationAutomatic && requested != RigidRepresentationThetaSeries &&
            requested != RigidRepresentationEllipticIntegral)
        return RigidStatusUnknownRepresentation;
    if (rigidRotorSetUp(r, shape, omega, attitude))
        return rigidRotorInitializeAsymmetric(r, requested, fused, t, fusedValue);
    return RigidStatusOk;
}

/** The state at time t (any finite t, in the time unit of omega) of the rotor r. */
RIGID_FUNCTION void rigidRotorEvolve(const RigidRotor* r, double t, double* omega, double attitude[3][3]) {
    double rotation[3][3], attitude0[3][3], x[3];
    int k, j;
    if (r->steady || r->kind == RigidKindSymmetric)
        for (k = 0; k < 3; k++)
            for (j = 0; j < 3; j++)
                attitude0[k][j] = r->attitude0[k][j];
    if (r->steady) {
        for (k = 0; k < 3; k++) {
            omega[k] = r->omega0[k];
            x[k] = r->omega0[k]*-t;
        }
        rigidRotationMatrix(x, rotation);
        rigidMultiply(rotation, attitude0, attitude);
        return;
    }
    if (r->kind == RigidKindSymmetric) {
        /* vZS eqs. (3.26)-(3.31): omega(t) = U(-wp t e) omega(0), A(t) = U(-wp t e) U(-L(0) t / I_perp) A(0). */
        double precession[3][3], spin[3][3], spun[3][3], axis[3];
        const double perpendicular = r->moments[(r->uniqueAxis + 1)%3];
        for (k = 0; k < 3; k++) {
            axis[k] = 0.0;
            x[k] = r->moments[k]*r->omega0[k]*(-t/perpendicular);
        }
        axis[r->uniqueAxis] = -r->symmetricPrecession*t;
        rigidRotationMatrix(axis, precession);
        rigidRotationMatrix(x, spin);
        rigidMultiplyVector(precession, r->omega0, omega);
        rigidMultiply(spin, attitude0, spun);
        rigidMultiply(precession, spun, attitude);
        return;
    }
    {
        /* Asymmetric top: vZS eqs. (3.33)-(3.35), then A = Q^T T1'(omega(t)) T2'(psi) B. */
        const double scaledTime = t*r->frequencyScale;  /* exact: frequencyScale is a power of two */
        const double u = r->wp*scaledTime + r->epsilon;
        if (r->representation == RigidRepresentationThetaSeries) {
            RigidThetaValues value;
            double cosPsi, sinPsi, derivative, sum;
            rigidThetaSeries(r, 1, &u, &value, &derivative, &sum);
            rigidThetaPrecession(r, scaledTime, &value, &cosPsi, &sinPsi);
            rigidRotorCompose(r, value.sn, value.cn, value.dn, cosPsi, sinPsi, omega, attitude);
        }
        else {
            RigidJacobi f;
            double psi, sinPsi, cosPsi;
            rigidJacobiElliptic(u, r->m, r->m1, &f);
            /* psi = (L/I3) t + P (Pi(u) - Pi(eps)) with Pi(u) = u + excess(u) and P wp = L (I3 - I1)/(I1 I3). */
            psi = r->angularMomentum/r->internalMoments[0]*scaledTime +
                  r->integralPrefactor*(rigidPrecessionAngleExcess(r, u, &f) - r->integralAtStart);
            rigidSinCos(psi, &sinPsi, &cosPsi);
            rigidRotorCompose(r, f.sn, f.cn, f.dn, cosPsi, sinPsi, omega, attitude);
        }
    }
}

/**
 * The integrator's entry point: the exact free rotation of a body over the time t, written over
 * (omega, attitude). The same result as rigidRotorInitialize() followed by rigidRotorEvolve(), with
 * the theta series at the start and at t summed in one pass.
 *
 * Contract (nothing is checked): shape comes from rigidClassifyMoments() (with RigidStatusOk); omega
 * (the body-frame angular velocity, 1/time) and t are finite; attitude (lab to body) is orthonormal
 * with determinant +1 to rounding. For a linear body the component of omega along its axis is set to
 * zero; a point keeps its attitude and gets omega = 0 (a caller may as well skip it). Under this
 * contract the status is always RigidStatusOk.
 */
RIGID_FUNCTION int rigidRotorAdvance(const RigidShape* shape, double* omega, double attitude[3][3], double t) {
    RigidRotor r;
    RigidThetaValues fusedValue;
    const int status = rigidRotorInitialize(&r, shape, omega, attitude, RigidRepresentationAutomatic, 1, t, &fusedValue);
    if (status != RigidStatusOk)
        return status;
    if (r.kind == RigidKindAsymmetric && !r.steady && r.representation == RigidRepresentationThetaSeries) {
        double cosPsi, sinPsi;
        rigidThetaPrecession(&r, t*r.frequencyScale, &fusedValue, &cosPsi, &sinPsi);
        rigidRotorCompose(&r, fusedValue.sn, fusedValue.cn, fusedValue.dn, cosPsi, sinPsi, omega, attitude);
    }
    else
        rigidRotorEvolve(&r, t, omega, attitude);
    return RigidStatusOk;
}

#endif /* OPENMMRIGID_CORE_ROTOR_H_ */
