/*
 * The numerics core, part 3b: rigidRotorAdvance() for RigidLanes bodies at once, for the host
 * platforms (Reference and CPU). A GPU runs one body per thread, which is a lane already, so the
 * kernel source does not include this file; it is C99 like the rest of the core (tests/core/
 * compiles it so) and only the host's C++ (numerics/RigidCore.h) uses it.
 *
 * Why: the initialization of an asymmetric top is a chain of dependent square roots, divisions and
 * short loops (the nome and theta constants, Carlson's RF for eta and eps, the theta series at eps
 * and at t), which a processor runs one body at a time at the latency of each operation. Here every
 * stage runs for RigidLanes bodies side by side, in loops over the lanes of fixed length: the host
 * compiler turns them into vector instructions, and the independent chains of the bodies overlap.
 *
 * What runs in lanes: the theta-series path of the automatic representation (an asymmetric top that
 * is not steady, with m <= rigidAutomaticThetaSeriesLimit()), which is every body of rigid water but
 * a few in a million. The set-up and the axis ordering run body by body through the scalar core's
 * functions; the invariants, the initial argument, A1 and A2, B and the composition run in loops over
 * the lanes through the element functions the scalar path is built from (rigidInvariantsOf,
 * rigidInitialArgumentOf, rigidThetaAngles, rigidInvariantFrame, rigidPrecessionAngle,
 * rigidComposeInternal). Every other body (another kind, a steady rotation, m above the limit)
 * takes rigidRotorAdvance() itself.
 *
 * The lane forms of rigidThetaConstants(), rigidThetaPhase() (with rigidCarlsonRFLockstep()) and
 * rigidThetaSeries() below carry out the same operations, in the same order, on each lane as the
 * scalar functions do on one body; a lane whose loop has ended (its theta terms summed, its RF
 * duplications done) keeps its values while its lane-mates go on. The result is therefore the
 * scalar result bit for bit, whichever bodies share the lanes (tests/TestFreeRotor.cpp checks it in
 * every regime; the host build adds no floating-point contraction that the scalar build lacks).
 * See CoreRotor.h for the equations.
 */
#ifndef OPENMMRIGID_CORE_ROTOR_LANES_H_
#define OPENMMRIGID_CORE_ROTOR_LANES_H_

/** Bodies advanced side by side: four doubles fill an AVX2 register, two SSE2 registers. */
enum { RigidLanes = 4 };

/* A loop over the lanes; the translation unit that vectorizes them defines it (openmmapi/src/RotorLanes.cpp). */
#ifndef RIGID_LANE_LOOP
#define RIGID_LANE_LOOP
#endif

/**
 * rigidThetaConstants() for every lane: the nome, the number of terms, K, the scale of the argument
 * and of the Jacobi functions, written into r[l]. Returns 0 if a lane's series did not converge in
 * RigidMaxThetaTerms terms (never for m <= rigidAutomaticThetaSeriesLimit()).
 */
RIGID_HOT_FUNCTION int rigidThetaConstantsLanes(RigidRotor* r) {
    double m[RigidLanes], m1[RigidLanes], nome[RigidLanes], nome2[RigidLanes], active[RigidLanes];
    double theta2[RigidLanes], theta3[RigidLanes], theta4[RigidLanes], terms[RigidLanes];
    double oddPower[RigidLanes], oddStep[RigidLanes], evenPower[RigidLanes], evenStep[RigidLanes];
    int l, n, running = 1;
    RIGID_LANE_LOOP
    for (l = 0; l < RigidLanes; l++) {
        m[l] = r[l].m;
        m1[l] = r[l].m1;
    }
    /* the nome series in the smaller of m and m1 (rigidThetaConstants) */
    RIGID_LANE_LOOP
    for (l = 0; l < RigidLanes; l++) {
        const double p = (m[l] <= 0.5 ? m1[l] : m[l]), complement = (m[l] <= 0.5 ? m[l] : m1[l]);
        nome[l] = rigidJacobiNome(sqrt(sqrt(p)), complement);
    }
    RIGID_LANE_LOOP
    for (l = 0; l < RigidLanes; l++)
        if (!(m[l] <= 0.5))
            nome[l] = exp(rigidPi()*rigidPi()/log(nome[l]));
    RIGID_LANE_LOOP
    for (l = 0; l < RigidLanes; l++) {
        theta2[l] = 0.0;
        theta3[l] = theta4[l] = 1.0;
        oddPower[l] = evenPower[l] = 1.0;
        oddStep[l] = nome[l]*nome[l];
        evenStep[l] = nome[l];
        nome2[l] = nome[l]*nome[l];
        active[l] = 1.0;
        terms[l] = 0.0;
    }
    for (n = 0; n < RigidMaxThetaTerms && running; n++) {
        const double sign = (n%2 == 0 ? 2.0 : -2.0), later = (n > 0 ? 1.0 : 0.0);
        running = 0;
        RIGID_LANE_LOOP
        for (l = 0; l < RigidLanes; l++) {
            const double sum2 = theta2[l] + oddPower[l], sum3 = theta3[l] + 2.0*evenPower[l];
            const double sum4 = theta4[l] + sign*evenPower[l];
            theta2[l] = (active[l] != 0.0 ? sum2 : theta2[l]);
            theta3[l] = (active[l]*later != 0.0 ? sum3 : theta3[l]);
            theta4[l] = (active[l]*later != 0.0 ? sum4 : theta4[l]);
            terms[l] = (active[l] != 0.0 ? n + 1.0 : terms[l]);
            active[l] = (evenPower[l] < 0.25*rigidEpsilon() ? active[l]*(1.0 - later) : active[l]);
            oddPower[l] *= oddStep[l];
            oddStep[l] *= nome2[l];
            evenPower[l] *= evenStep[l];
            evenStep[l] *= nome2[l];
        }
        RIGID_LANE_LOOP
        for (l = 0; l < RigidLanes; l++)
            running |= (active[l] != 0.0);
    }
    RIGID_LANE_LOOP
    for (l = 0; l < RigidLanes; l++) {
        r[l].nome = nome[l];
        r[l].thetaTerms = (int) terms[l];
        /* K = (pi/2) theta_3(0|q)^2 (DLMF 20.9.2) */
        r[l].quarterPeriod = 0.5*rigidPi()*theta3[l]*theta3[l];
        r[l].thetaScale = rigidPi()/(2.0*r[l].quarterPeriod);
        r[l].snScale = theta3[l]/theta2[l];
        r[l].cnScale = theta4[l]/theta2[l];
        r[l].dnScale = theta4[l]/theta3[l];
    }
    return !running;
}

/**
 * rigidThetaPhase() for every lane (eta, eps and the hyperbolic functions of x = pi eta / 2K), its two
 * RF integrals per lane duplicated as rigidCarlsonRFLockstep() does: a lane duplicates until both of
 * its integrals have reached their stopping point, then holds.
 */
RIGID_HOT_FUNCTION void rigidThetaPhaseLanes(RigidRotor* r, const RigidJacobi* f0) {
    /* integral k of lane l at index i = k RigidLanes + l: k = 0 gives eta, k = 1 eps */
    double x[2*RigidLanes], y[2*RigidLanes], z[2*RigidLanes], mean[2*RigidLanes], mean0[2*RigidLanes];
    double x0[2*RigidLanes], y0[2*RigidLanes], q[2*RigidLanes], rf[2*RigidLanes], scale[2*RigidLanes], active[2*RigidLanes];
    double cSquared[RigidLanes], expm1x[RigidLanes], xs[RigidLanes];
    int l, i, n, running = 1;
    RIGID_LANE_LOOP
    for (l = 0; l < RigidLanes; l++) {
        const double m = r[l].m, i1 = r[l].internalMoments[0], i3 = r[l].internalMoments[2];
        const double l3 = i3*r[l].w3m, c = (i1*r[l].w1m)*(i1*r[l].w1m);
        x[l] = m*l3*l3;
        x[RigidLanes + l] = f0[l].cn*f0[l].cn;
        y[l] = m*r[l].angularMomentum*r[l].angularMomentum;
        y[RigidLanes + l] = f0[l].dn*f0[l].dn;
        z[l] = m*l3*l3 + c;
        z[RigidLanes + l] = 1.0;
        cSquared[l] = c;
    }
    RIGID_LANE_LOOP
    for (i = 0; i < 2*RigidLanes; i++) {
        mean[i] = mean0[i] = (x[i] + y[i] + z[i])/3.0;
        x0[i] = x[i];
        y0[i] = y[i];
        q[i] = rigidRFStopFactor()*rigidMax3(fabs(mean[i] - x[i]), fabs(mean[i] - y[i]), fabs(mean[i] - z[i]));
        scale[i] = 1.0;
    }
    for (n = 0; n < RigidMaxDuplications && running; n++) {
        running = 0;
        RIGID_LANE_LOOP
        for (l = 0; l < RigidLanes; l++) {
            const double on = (q[l]*scale[l] >= fabs(mean[l]) || q[RigidLanes + l]*scale[l] >= fabs(mean[RigidLanes + l]) ?
                               1.0 : 0.0);
            active[l] = active[RigidLanes + l] = on;
        }
        RIGID_LANE_LOOP
        for (l = 0; l < RigidLanes; l++)
            running |= (active[l] != 0.0);
        if (!running)
            break;
        /* DLMF 19.26.18, as in rigidCarlsonRFLockstep (scale[i] is the lane's 4^-n for both integrals) */
        RIGID_LANE_LOOP
        for (i = 0; i < 2*RigidLanes; i++) {
            const double sx = sqrt(x[i]), sy = sqrt(y[i]), sz = sqrt(z[i]);
            const double lambda = sx*sy + sy*sz + sz*sx;
            const double nextX = 0.25*(x[i] + lambda), nextY = 0.25*(y[i] + lambda);
            const double nextZ = 0.25*(z[i] + lambda), nextMean = 0.25*(mean[i] + lambda);
            x[i] = (active[i] != 0.0 ? nextX : x[i]);
            y[i] = (active[i] != 0.0 ? nextY : y[i]);
            z[i] = (active[i] != 0.0 ? nextZ : z[i]);
            mean[i] = (active[i] != 0.0 ? nextMean : mean[i]);
            scale[i] = (active[i] != 0.0 ? 0.25 : 1.0)*scale[i];
        }
    }
    RIGID_LANE_LOOP
    for (i = 0; i < 2*RigidLanes; i++) {
        /* DLMF 19.36.1, as in rigidCarlsonRFLockstep */
        const double dx = (mean0[i] - x0[i])*scale[i]/mean[i];
        const double dy = (mean0[i] - y0[i])*scale[i]/mean[i];
        const double dz = -dx - dy;
        const double e2 = dx*dy - dz*dz;
        const double e3 = dx*dy*dz;
        rf[i] = (1.0 - e2/10.0 + e3/14.0 + e2*e2/24.0 - 3.0*e2*e3/44.0 - 5.0*e2*e2*e2/208.0 + 3.0*e3*e3/104.0 +
                 e2*e2*e3/16.0)/sqrt(mean[i]);
    }
    RIGID_LANE_LOOP
    for (l = 0; l < RigidLanes; l++) {
        const double eta = (r[l].w3m < 0.0 ? -1.0 : 1.0)*sqrt(cSquared[l])*rf[l];
        r[l].epsilon = f0[l].sn*rf[RigidLanes + l];
        xs[l] = r[l].thetaScale*eta;
    }
    RIGID_LANE_LOOP
    for (l = 0; l < RigidLanes; l++)
        expm1x[l] = expm1(xs[l]);
    RIGID_LANE_LOOP
    for (l = 0; l < RigidLanes; l++) {
        const double sinhX = 0.5*expm1x[l]*(1.0 + 1.0/(1.0 + expm1x[l]));
        const double coshX = sqrt(1.0 + sinhX*sinhX);
        r[l].sinhX = sinhX;
        r[l].coshX = coshX;
        r[l].sinh2X = 2.0*sinhX*coshX;
        r[l].cosh2X = 1.0 + 2.0*sinhX*sinhX;
    }
}

/**
 * rigidSinCos() of x[l] into s[l] and c[l] for every lane: the branch-free rigidSinCosReduced() in a
 * loop over the lanes, which vectorizes, then rigidSinCos() itself for the rare lane beyond its range.
 */
RIGID_HOT_FUNCTION void rigidSinCosLanes(const double* x, double* s, double* c) {
    int l;
    RIGID_LANE_LOOP
    for (l = 0; l < RigidLanes; l++)
        rigidSinCosReduced(x[l], &s[l], &c[l]);
    for (l = 0; l < RigidLanes; l++)
        if (!(fabs(x[l]) <= RIGID_SIN_COS_LIMIT))
            rigidSinCos(x[l], &s[l], &c[l]);
}

/** rigidThetaSeries()'s values at two arguments j = 0, 1 for each lane l, at [j][l]. */
typedef struct {
    double sn[2][RigidLanes], cn[2][RigidLanes], dn[2][RigidLanes], re[2][RigidLanes], im[2][RigidLanes];
} RigidThetaLanes;

/**
 * rigidThetaSeries() with two arguments per lane, u[0][l] and u[1][l], each lane with its own
 * coefficients and number of terms; the sums of a lane stop at its own last term.
 */
RIGID_HOT_FUNCTION void rigidThetaSeriesLanes(const RigidRotor* r, double u[2][RigidLanes], RigidThetaLanes* values,
                                              double* derivative, double* value) {
    double so[2][RigidLanes], co[2][RigidLanes], se[2][RigidLanes], ce[2][RigidLanes], s2[2][RigidLanes], c2[2][RigidLanes];
    double theta1[2][RigidLanes], theta2[2][RigidLanes], theta3[2][RigidLanes], theta4[2][RigidLanes];
    double re[2][RigidLanes], im[2][RigidLanes], zeta[2][RigidLanes];
    double nome2[RigidLanes], oddPower[RigidLanes], oddStep[RigidLanes], evenPower[RigidLanes], evenStep[RigidLanes];
    double sinhK[RigidLanes], coshK[RigidLanes], sinh2X[RigidLanes], cosh2X[RigidLanes], terms[RigidLanes];
    double cr[RigidLanes], ci[RigidLanes], sumDerivative[RigidLanes], sumValue[RigidLanes];
    double snScale[RigidLanes], cnScale[RigidLanes], dnScale[RigidLanes];
    int j, l, n, mostTerms = 1;
    RIGID_LANE_LOOP
    for (l = 0; l < RigidLanes; l++) {
        nome2[l] = r[l].nome*r[l].nome;
        oddPower[l] = 1.0;
        oddStep[l] = nome2[l];
        evenPower[l] = 1.0;
        evenStep[l] = r[l].nome;
        sinhK[l] = r[l].sinhX;
        coshK[l] = r[l].coshX;
        sinh2X[l] = r[l].sinh2X;
        cosh2X[l] = r[l].cosh2X;
        terms[l] = r[l].thetaTerms;
        if (r[l].thetaTerms > mostTerms)
            mostTerms = r[l].thetaTerms;
        zeta[0][l] = r[l].thetaScale*u[0][l];
        zeta[1][l] = r[l].thetaScale*u[1][l];
        snScale[l] = r[l].snScale;
        cnScale[l] = r[l].cnScale;
        dnScale[l] = r[l].dnScale;
    }
    RIGID_LANE_LOOP
    for (l = 0; l < RigidLanes; l++) {
        cr[l] = 2.0*oddPower[l]*coshK[l];
        ci[l] = -2.0*oddPower[l]*sinhK[l];
        sumDerivative[l] = 0.0 + cr[l];
        sumValue[l] = 0.0 - ci[l];
    }
    for (j = 0; j < 2; j++)
        rigidSinCosLanes(zeta[j], so[j], co[j]);
    for (j = 0; j < 2; j++)
        RIGID_LANE_LOOP
        for (l = 0; l < RigidLanes; l++) {
            s2[j][l] = se[j][l] = 2.0*so[j][l]*co[j][l];
            c2[j][l] = ce[j][l] = (co[j][l] - so[j][l])*(co[j][l] + so[j][l]);
            theta1[j][l] = oddPower[l]*so[j][l];
            theta2[j][l] = oddPower[l]*co[j][l];
            theta3[j][l] = theta4[j][l] = 1.0;
            re[j][l] = cr[l]*so[j][l];
            im[j][l] = ci[l]*co[j][l];
        }
    for (n = 1; n < mostTerms; n++) {
        const double sign = (n%2 == 0 ? 2.0 : -2.0), parity = (n%2 == 0 ? 1.0 : -1.0), weight = 2*n + 1, term = n;
        RIGID_LANE_LOOP
        for (l = 0; l < RigidLanes; l++) {
            double nextSinh, nextDerivative, nextValue;
            oddPower[l] *= oddStep[l];
            oddStep[l] *= nome2[l];
            evenPower[l] *= evenStep[l];
            evenStep[l] *= nome2[l];
            nextSinh = sinhK[l]*cosh2X[l] + coshK[l]*sinh2X[l];
            coshK[l] = coshK[l]*cosh2X[l] + sinhK[l]*sinh2X[l];
            sinhK[l] = nextSinh;
            cr[l] = sign*oddPower[l]*coshK[l];
            ci[l] = -sign*oddPower[l]*sinhK[l];
            nextDerivative = sumDerivative[l] + weight*cr[l];
            nextValue = sumValue[l] - ci[l];
            sumDerivative[l] = (term < terms[l] ? nextDerivative : sumDerivative[l]);
            sumValue[l] = (term < terms[l] ? nextValue : sumValue[l]);
        }
        for (j = 0; j < 2; j++)
            RIGID_LANE_LOOP
            for (l = 0; l < RigidLanes; l++) {
                /* (-1)^n q^{n(n+1)} and (-1)^n 2 q^{n^2}: a product by +-1 is exact */
                const double signedOdd = parity*oddPower[l];
                const double even = 2.0*evenPower[l];
                const double signedEven = parity*even;
                const double nextOdd = so[j][l]*c2[j][l] + co[j][l]*s2[j][l];
                const double nextCo = co[j][l]*c2[j][l] - so[j][l]*s2[j][l];
                const double sum3 = theta3[j][l] + even*ce[j][l], sum4 = theta4[j][l] + signedEven*ce[j][l];
                const double sumRe = re[j][l] + cr[l]*nextOdd, sumIm = im[j][l] + ci[l]*nextCo;
                const double sum1 = theta1[j][l] + signedOdd*nextOdd, sum2 = theta2[j][l] + oddPower[l]*nextCo;
                double nextEven;
                co[j][l] = nextCo;
                so[j][l] = nextOdd;
                theta3[j][l] = (term < terms[l] ? sum3 : theta3[j][l]);
                theta4[j][l] = (term < terms[l] ? sum4 : theta4[j][l]);
                re[j][l] = (term < terms[l] ? sumRe : re[j][l]);
                im[j][l] = (term < terms[l] ? sumIm : im[j][l]);
                theta1[j][l] = (term < terms[l] ? sum1 : theta1[j][l]);
                theta2[j][l] = (term < terms[l] ? sum2 : theta2[j][l]);
                nextEven = se[j][l]*c2[j][l] + ce[j][l]*s2[j][l];
                ce[j][l] = ce[j][l]*c2[j][l] - se[j][l]*s2[j][l];
                se[j][l] = nextEven;
            }
    }
    for (j = 0; j < 2; j++)
        RIGID_LANE_LOOP
        for (l = 0; l < RigidLanes; l++) {
            values->sn[j][l] = snScale[l]*theta1[j][l]/theta4[j][l];
            values->cn[j][l] = cnScale[l]*theta2[j][l]/theta4[j][l];
            values->dn[j][l] = dnScale[l]*theta3[j][l]/theta4[j][l];
            values->re[j][l] = re[j][l];
            values->im[j][l] = im[j][l];
        }
    for (l = 0; l < RigidLanes; l++) {
        derivative[l] = sumDerivative[l];
        value[l] = sumValue[l];
    }
}

/**
 * The end of rigidRotorAdvance()'s theta-series path for every lane, from the series at eps (index 0
 * of values, with its sums derivative and value) and at the time t (index 1): rigidThetaFinish(),
 * rigidRotorAsymmetricFinish(), rigidThetaPrecession() and rigidRotorCompose(), through the same
 * element functions (rigidThetaAngles, rigidInvariantFrame, rigidMultiplyTransposed,
 * rigidPrecessionAngle, rigidComposeInternal). Writes omega and the attitude in internal axes, at [k][l]
 * and [j][c][l]; the caller takes them to the given axes.
 */
RIGID_HOT_FUNCTION void rigidRotorFinishLanes(const RigidRotor* r, const RigidThetaLanes* values, const double* derivative,
                                              const double* value, const double* scale, double t, double w[3][RigidLanes],
                                              double internal[3][3][RigidLanes]) {
    double i1w1m[RigidLanes], i2w2m[RigidLanes], i3w3m[RigidLanes], angularMomentum[RigidLanes], i1[RigidLanes];
    double thetaScale[RigidLanes], wp[RigidLanes], w1m[RigidLanes], w2m[RigidLanes], w3m[RigidLanes];
    double phase2[RigidLanes], cosPhase1[RigidLanes], sinPhase1[RigidLanes], angle[RigidLanes], c2[RigidLanes], s2[RigidLanes];
    double qa[3][3][RigidLanes];
    int l, j, c;
    for (l = 0; l < RigidLanes; l++) {
        /* the products that rigidBodyToInvariantFrame forms first */
        i1w1m[l] = r[l].internalMoments[0]*r[l].w1m;
        i2w2m[l] = r[l].internalMoments[1]*r[l].w2m;
        i3w3m[l] = r[l].internalMoments[2]*r[l].w3m;
        angularMomentum[l] = r[l].angularMomentum;
        i1[l] = r[l].internalMoments[0];
        thetaScale[l] = r[l].thetaScale;
        wp[l] = r[l].wp;
        w1m[l] = r[l].w1m;
        w2m[l] = r[l].w2m;
        w3m[l] = r[l].w3m;
        /* Q A(0) (rigidRotorAsymmetricFinish) */
        for (j = 0; j < 3; j++)
            for (c = 0; c < 3; c++)
                qa[j][c][l] = r[l].axisSign[j]*r[l].attitude0[r[l].axisOf[j]][c];
    }
    RIGID_LANE_LOOP
    for (l = 0; l < RigidLanes; l++) {
        rigidThetaAngles(angularMomentum[l], i1[l], thetaScale[l], wp[l], derivative[l], value[l], values->re[0][l],
                         values->im[0][l], &phase2[l], &cosPhase1[l], &sinPhase1[l]);
        angle[l] = phase2[l]*(t*scale[l]);
    }
    rigidSinCosLanes(angle, s2, c2);
    RIGID_LANE_LOOP
    for (l = 0; l < RigidLanes; l++) {
        double t1[3][3], a[3][3], b[3][3], rotated[3][3], cosPsi, sinPsi;
        for (j = 0; j < 3; j++)
            for (c = 0; c < 3; c++)
                a[j][c] = qa[j][c][l];
        /* B = T1'(omega(0))^T Q A(0) */
        rigidInvariantFrame(i1w1m[l]*values->cn[0][l], i2w2m[l]*values->sn[0][l], i3w3m[l]*values->dn[0][l],
                            angularMomentum[l], t1);
        rigidMultiplyTransposed(t1, a, b);
        /* psi, then T1'(omega(t)) T2'(psi) B */
        rigidPrecessionAngle(cosPhase1[l], sinPhase1[l], c2[l], s2[l], values->re[1][l], values->im[1][l], &cosPsi, &sinPsi);
        rigidInvariantFrame(i1w1m[l]*values->cn[1][l], i2w2m[l]*values->sn[1][l], i3w3m[l]*values->dn[1][l],
                            angularMomentum[l], t1);
        rigidComposeInternal(t1, cosPsi, sinPsi, &b[0][0], rotated);
        for (j = 0; j < 3; j++)
            for (c = 0; c < 3; c++)
                internal[j][c][l] = rotated[j][c];
        w[0][l] = w1m[l]*values->cn[1][l]*scale[l];
        w[1][l] = w2m[l]*values->sn[1][l]*scale[l];
        w[2][l] = w3m[l]*values->dn[1][l]*scale[l];
    }
}

/**
 * The start of rigidRotorAdvance() for an asymmetric top in every lane: rigidRotorAsymmetricStart()'s
 * invariants and initial argument (rigidInvariantsOf, rigidInitialArgumentOf) from the internal
 * moments of r[l] and w0[l], the scaled omega in internal axes, into v[l] and f0[l]. moving[l] is 1
 * where both succeed (rigidRotorAsymmetricStart() would return 1), else 0.
 */
RIGID_HOT_FUNCTION void rigidRotorStartLanes(const RigidRotor* r, double w0[][3], RigidInvariants* v, RigidJacobi* f0,
                                             int* moving) {
    int l;
    RIGID_LANE_LOOP
    for (l = 0; l < RigidLanes; l++) {
        /* both evaluated, so that the lanes run no branch; rigidInitialArgumentOf only divides */
        const int found = rigidInvariantsOf(r[l].internalMoments, w0[l], &v[l]);
        const int started = rigidInitialArgumentOf(&v[l], w0[l], &f0[l]);
        moving[l] = found & started;
    }
}

/**
 * rigidRotorAdvance() for count <= RigidLanes bodies: shapes[b], omega[b] and attitude[b] as that
 * function takes them, and the same time t for all. Body b runs in lane b if it is an asymmetric
 * top on the theta-series path; every other body takes rigidRotorAdvance() itself, and its lane
 * repeats a lane that runs, so that it computes nothing out of the ordinary. The results are
 * rigidRotorAdvance()'s bit for bit. Same contract; the status is always RigidStatusOk under it.
 */
RIGID_HOT_FUNCTION int rigidRotorAdvanceLanes(int count, const RigidShape* shapes, double omega[][3], double attitude[][3][3],
                                              double t) {
    RigidRotor r[RigidLanes];
    RigidJacobi f0[RigidLanes];
    RigidInvariants invariants[RigidLanes];
    RigidThetaLanes values;
    double scale[RigidLanes], u[2][RigidLanes], derivative[RigidLanes], value[RigidLanes];
    double w0[RigidLanes][3], w[3][RigidLanes], internal[3][3][RigidLanes];
    int candidate[RigidLanes], moving[RigidLanes], taken[RigidLanes], first = -1, b, l, j, c;
    if (count > RigidLanes)
        return RigidStatusUnknownRepresentation;
    /* rigidRotorSetUp, then rigidRotorAsymmetricStart's scaling and axis ordering, for each body */
    for (b = 0; b < count; b++) {
        candidate[b] = (shapes[b].kind == RigidKindAsymmetric && rigidRotorSetUp(&r[b], &shapes[b], omega[b], attitude[b]));
        if (candidate[b]) {
            double scaledOmega[3];
            scale[b] = rigidRotorScaleFrequency(r[b].omega0, scaledOmega);
            rigidRotorOrderAxes(&r[b], scaledOmega, w0[b]);
            if (first < 0)
                first = b;
        }
    }
    if (first < 0) {
        for (b = 0; b < count; b++)
            rigidRotorAdvance(&shapes[b], omega[b], attitude[b], t);
        return RigidStatusOk;
    }
    for (l = 0; l < RigidLanes; l++)
        if (l >= count || !candidate[l]) {
            r[l] = r[first];
            scale[l] = scale[first];
            for (j = 0; j < 3; j++)
                w0[l][j] = w0[first][j];
        }
    rigidRotorStartLanes(r, w0, invariants, f0, moving);
    /* the bodies on the theta-series path stay in their lanes; the others take the scalar path */
    first = -1;
    for (b = 0; b < count; b++) {
        taken[b] = (candidate[b] && moving[b] && invariants[b].m <= rigidAutomaticThetaSeriesLimit() &&
                    invariants[b].m1 != 0.0);
        if (taken[b]) {
            rigidRotorTakeInvariants(&r[b], &invariants[b]);
            if (first < 0)
                first = b;
        }
        else
            rigidRotorAdvance(&shapes[b], omega[b], attitude[b], t);
    }
    if (first < 0)
        return RigidStatusOk;
    for (l = 0; l < RigidLanes; l++)
        if (l >= count || !taken[l]) {
            r[l] = r[first];
            f0[l] = f0[first];
            scale[l] = scale[first];
        }
    if (!rigidThetaConstantsLanes(r)) {
        /* not reached for m <= rigidAutomaticThetaSeriesLimit(); the scalar path reports it */
        for (b = 0; b < count; b++)
            if (taken[b])
                rigidRotorAdvance(&shapes[b], omega[b], attitude[b], t);
        return RigidStatusOk;
    }
    rigidThetaPhaseLanes(r, f0);
    RIGID_LANE_LOOP
    for (l = 0; l < RigidLanes; l++) {
        u[0][l] = r[l].epsilon;
        u[1][l] = r[l].wp*(t*scale[l]) + r[l].epsilon;
    }
    rigidThetaSeriesLanes(r, u, &values, derivative, value);
    rigidRotorFinishLanes(r, &values, derivative, value, scale, t, w, internal);
    /* A = Q^T (T1' T2' B) and omega in the given axes (rigidRotorCompose) */
    for (b = 0; b < count; b++)
        if (taken[b])
            for (j = 0; j < 3; j++) {
                const int axis = r[b].axisOf[j];
                const double sign = r[b].axisSign[j];
                omega[b][axis] = sign*w[j][b];
                for (c = 0; c < 3; c++)
                    attitude[b][axis][c] = sign*internal[j][c][b];
            }
    return RigidStatusOk;
}

#endif /* OPENMMRIGID_CORE_ROTOR_LANES_H_ */
