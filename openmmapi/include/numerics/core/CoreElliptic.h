/*
 * The numerics core, part 2: Carlson's symmetric integrals RF and RJ, the complete elliptic integral
 * K and the Jacobi elliptic functions sn, cn, dn, on plain doubles with no checks (the callers'
 * contracts are stated at each function; numerics/Elliptic.h wraps these with the argument checks
 * and exceptions of the public API). See numerics/RigidCore.h for the rules every core file follows.
 *
 * Convention: everything takes the PARAMETER m (not the modulus k = sqrt(m)) and, as a separate
 * argument, its complement m1 = 1 - m, which the caller usually knows to full relative precision
 * near m = 1; every function uses m1 wherever 1 - m appears. The domain is 0 <= m <= 1.
 *
 * Accuracy (double precision, checked against mpmath in tests/python/test_special_functions.py):
 * - rigidCarlsonRF, rigidCarlsonRJ: a few ulps; the duplication runs until the Taylor remainder is
 *   below machine precision (Carlson, Numer. Algorithms 10 (1995) 13).
 * - rigidEllipticK: a few ulps relative.
 * - rigidJacobiElliptic: a few ulps relative to |f| + |u f'|, i.e. exact up to the rounding of u
 *   itself, also near m = 1 where cn and dn are exponentially small.
 * Every loop has a fixed bound, far above what any finite argument needs (stated at each loop).
 */
#ifndef OPENMMRIGID_CORE_ELLIPTIC_H_
#define OPENMMRIGID_CORE_ELLIPTIC_H_

/*
 * Duplication in Carlson's algorithms stops once 4^-n Q < |A_n|, with Q = (3 eps)^(-1/8) max|A_0 - x|
 * for RF (whose series keeps the seventh-order terms of DLMF 19.36.1, one duplication fewer than the
 * fifth-order series needs) and (eps/4)^(-1/6) max|A_0 - x| for RJ: the Taylor remainder is then
 * below machine precision (Carlson, Numer. Algorithms 10 (1995) 13, eqs. (2.2) and (2.36)). The two
 * factors, pow(3 eps, -1/8) and pow(eps/4, -1/6) rounded to double, are written out (tests check them
 * against pow).
 */
RIGID_FUNCTION double rigidRFStopFactor(void) {
    return 0x1.3b9578eb0bf54p+6;   /* 78.895969078640803 */
}

RIGID_FUNCTION double rigidRJStopFactor(void) {
    return 0x1.ffffffffffffdp+8;   /* 511.99999999999983 */
}

/*
 * The most duplications of RF or RJ. Each one divides the spread of the arguments by about 4 once
 * they are within a factor of a few of each other, and takes a square root of their ratio before:
 * arguments spanning the whole double range (1e-308 to 1e308) converge in about 40.
 */
enum { RigidMaxDuplications = 200 };

/**
 * RF(x[k], y[k], z[k]) for count = 1 or 2 argument triples at once (see rigidCarlsonRF). The
 * duplications of the two integrals run in lockstep until both have reached their stopping point, so
 * that their square roots overlap in the processor; a duplication beyond an integral's own stopping
 * point only makes its Taylor remainder smaller. Contract: finite, non-negative arguments with at
 * most one zero per triple. x, y and z are overwritten.
 */
RIGID_HOT_FUNCTION void rigidCarlsonRFLockstep(int count, double* x, double* y, double* z, double* result) {
    double mean[2], mean0[2], x0[2], y0[2], q[2];
    double scale = 1.0;  /* 4^-n */
    int k, n;
    for (k = 0; k < count; k++) {
        mean[k] = mean0[k] = (x[k] + y[k] + z[k])/3.0;
        x0[k] = x[k];
        y0[k] = y[k];
        q[k] = rigidRFStopFactor()*rigidMax3(fabs(mean[k] - x[k]), fabs(mean[k] - y[k]), fabs(mean[k] - z[k]));
    }
    for (n = 0; n < RigidMaxDuplications; n++) {
        int converged = 1;
        for (k = 0; k < count; k++)
            if (q[k]*scale >= fabs(mean[k]))
                converged = 0;
        if (converged)
            break;
        /* DLMF 19.26.18: RF(x, y, z) = RF((x + l)/4, (y + l)/4, (z + l)/4), l = sqrt(xy) + sqrt(yz) + sqrt(zx). */
        for (k = 0; k < count; k++) {
            const double sx = sqrt(x[k]), sy = sqrt(y[k]), sz = sqrt(z[k]);
            const double lambda = sx*sy + sy*sz + sz*sx;
            x[k] = 0.25*(x[k] + lambda);
            y[k] = 0.25*(y[k] + lambda);
            z[k] = 0.25*(z[k] + lambda);
            mean[k] = 0.25*(mean[k] + lambda);
        }
        scale *= 0.25;
    }
    for (k = 0; k < count; k++) {
        /* DLMF 19.36.1 in the elementary symmetric functions e2, e3 of the scaled deviations. */
        const double dx = (mean0[k] - x0[k])*scale/mean[k];
        const double dy = (mean0[k] - y0[k])*scale/mean[k];
        const double dz = -dx - dy;
        const double e2 = dx*dy - dz*dz;
        const double e3 = dx*dy*dz;
        result[k] = (1.0 - e2/10.0 + e3/14.0 + e2*e2/24.0 - 3.0*e2*e3/44.0 - 5.0*e2*e2*e2/208.0 + 3.0*e3*e3/104.0 +
                     e2*e2*e3/16.0)/sqrt(mean[k]);
    }
}

/**
 * Carlson's symmetric integral RF(x, y, z) = 1/2 int_0^inf dt / sqrt((t+x)(t+y)(t+z)) (DLMF 19.16.1),
 * by the duplication theorem (DLMF 19.26.18) and the seventh-order Taylor expansion of DLMF 19.36.1.
 * Contract: x, y, z finite and non-negative, at most one of them zero.
 */
RIGID_FUNCTION double rigidCarlsonRF(double x, double y, double z) {
    double result, xs = x, ys = y, zs = z;
    rigidCarlsonRFLockstep(1, &xs, &ys, &zs, &result);
    return result;
}

/**
 * Carlson's degenerate integral RC(1, 1 + e) for e > -1 (DLMF 19.2.17 and 19.2.18): atan(sqrt(e))/sqrt(e)
 * for e > 0 and atanh(sqrt(-e))/sqrt(-e) for e < 0, with a series near e = 0. The caller passes 1 + e
 * as well, computed without cancellation, since near e = -1 the result depends on it alone.
 */
RIGID_FUNCTION double rigidCarlsonRCOnePlus(double e, double onePlusE) {
    double s;
    if (fabs(e) < 1e-4)
        return 1.0 - e*(1.0/3.0 - e*(1.0/5.0 - e*(1.0/7.0 - e/9.0)));
    s = sqrt(fabs(e));
    if (e > 0.0)
        return atan(s)/s;
    if (e > -0.5)
        return atanh(s)/s;
    /* atanh(s) = ln((1 + s)/(1 - s))/2 and 1 - s = (1 + e)/(1 + s), exact near e = -1. */
    return log((1.0 + s)*(1.0 + s)/onePlusE)/(2.0*s);
}

/**
 * Carlson's symmetric integral RJ(x, y, z, p) = 3/2 int_0^inf dt / ((t+p) sqrt((t+x)(t+y)(t+z)))
 * (DLMF 19.16.2), by the duplication theorem with the RC correction terms of Carlson (1995),
 * eqs. (2.36)-(2.39), and DLMF 19.36.2. Contract: x, y, z finite and non-negative (at most one zero),
 * p finite and positive.
 *
 * The argument of each RC term is e = prod_k (sqrt(p) - sqrt(x_k)) / (sqrt(p) + sqrt(x_k)) (the
 * ratio delta 4^-3n / d_n^2 of Carlson's paper, factored); 1 + e is formed from the complements
 * a_k = 1 - |ratio_k| so that it keeps full precision when p is far from x, y, z and e nears -1.
 */
RIGID_FUNCTION double rigidCarlsonRJ(double x, double y, double z, double p) {
    double mean = (x + y + z + 2.0*p)/5.0;
    const double mean0 = mean, x0 = x, y0 = y, z0 = z;
    const double q = rigidRJStopFactor()*rigidMax4(fabs(mean - x), fabs(mean - y), fabs(mean - z), fabs(mean - p));
    double scale = 1.0;  /* 4^-n */
    double sum = 0.0;
    double dx, dy, dz, dp, e2, e3, e4, e5, series;
    int n, k;
    for (n = 0; n < RigidMaxDuplications && q*scale >= fabs(mean); n++) {
        const double sx = sqrt(x), sy = sqrt(y), sz = sqrt(z), sp = sqrt(p);
        const double lambda = sx*sy + sy*sz + sz*sx;
        const double d = (sp + sx)*(sp + sy)*(sp + sz);
        double e = 1.0, complement[3], sign = 1.0, roots[3], onePlusE;
        roots[0] = sx;
        roots[1] = sy;
        roots[2] = sz;
        for (k = 0; k < 3; k++) {
            const double ratio = (sp - roots[k])/(sp + roots[k]);
            complement[k] = 2.0*(roots[k] < sp ? roots[k] : sp)/(sp + roots[k]);  /* 1 - |ratio| */
            e *= ratio;
            if (ratio < 0.0)
                sign = -sign;
        }
        /* 1 + e; for sign -1 it is 1 - prod(1 - a_k) = a3 + (1 - a3)(a2 + (1 - a2) a1), a sum of positive terms. */
        onePlusE = (sign > 0.0 ? 1.0 + e :
                complement[2] + (1.0 - complement[2])*(complement[1] + (1.0 - complement[1])*complement[0]));
        sum += scale/d*rigidCarlsonRCOnePlus(e, onePlusE);
        x = 0.25*(x + lambda);
        y = 0.25*(y + lambda);
        z = 0.25*(z + lambda);
        p = 0.25*(p + lambda);
        mean = 0.25*(mean + lambda);
        scale *= 0.25;
    }
    dx = (mean0 - x0)*scale/mean;
    dy = (mean0 - y0)*scale/mean;
    dz = (mean0 - z0)*scale/mean;
    dp = -0.5*(dx + dy + dz);
    e2 = dx*dy + dx*dz + dy*dz - 3.0*dp*dp;
    e3 = dx*dy*dz + 2.0*e2*dp + 4.0*dp*dp*dp;
    e4 = (2.0*dx*dy*dz + e2*dp + 3.0*dp*dp*dp)*dp;
    e5 = dx*dy*dz*dp*dp;
    series = 1.0 - 3.0*e2/14.0 + e3/6.0 + 9.0*e2*e2/88.0 - 3.0*e4/22.0 - 9.0*e2*e3/52.0 + 3.0*e5/26.0;
    return scale*series/(mean*sqrt(mean)) + 6.0*sum;
}

/*
 * The most AGM steps of rigidEllipticK: the iteration converges quadratically once a and b agree to
 * a factor 2, which takes log2(log2(1/sqrt(m1))) steps before, under 10 for any positive double m1.
 */
enum { RigidMaxAGMSteps = 64 };

/**
 * The complete elliptic integral of the first kind K(m) = pi / (2 AGM(1, sqrt(m1))) (DLMF 19.8.5).
 * Contract: 0 <= m1 <= 1 (m enters only through m1); K is infinite at m1 = 0.
 */
RIGID_FUNCTION double rigidEllipticK(double m1) {
    double a = 1.0, b;
    int n;
    if (m1 == 0.0)
        return HUGE_VAL;
    b = sqrt(m1);
    for (n = 0; n < RigidMaxAGMSteps && fabs(a - b) > 2.0*rigidEpsilon()*a; n++) {
        const double next = 0.5*(a + b);
        b = sqrt(a*b);
        a = next;
    }
    return rigidPi()/(a + b);
}

/* sn, cn, dn of one argument */
typedef struct {
    double sn, cn, dn;
} RigidJacobi;

/** One term of the expansion about m = 1 of DLMF 22.10.2, used by rigidJacobiEllipticNearOne. */
RIGID_FUNCTION void rigidJacobiExpansionNearOne(double x, double m1, RigidJacobi* f) {
    const double t = tanh(x), h = 1.0/cosh(x);
    const double sinhCosh = sinh(x)*cosh(x);
    f->sn = t + 0.25*m1*(sinhCosh - x)*h*h;
    f->cn = h - 0.25*m1*(sinhCosh - x)*t*h;
    f->dn = h + 0.25*m1*(sinhCosh + x)*t*h;
}

/**
 * sn, cn, dn for m1 < 1e-32, where K = ln(4/sqrt(m1)) + O(m1) is at least 37. The argument is reduced
 * by the periods and symmetries (DLMF 22.4(ii)) to w in [0, K]; for w <= K/2 the expansion about
 * m = 1 of DLMF 22.10.2 (first order in m1; the next order is below (m1 e^{2w})^2 < 16 m1 relative)
 * gives the functions, and for w > K/2 the shift by K (DLMF 22.4.3),
 * sn(K - v) = cn(v)/dn(v), cn(K - v) = k' sn(v)/dn(v), dn(K - v) = k'/dn(v), brings the argument back
 * to v = K - w < K/2. Each result is a product of relatively accurate factors.
 */
RIGID_FUNCTION void rigidJacobiEllipticNearOne(double u, double m1, RigidJacobi* result) {
    const double quarter = log(4.0/sqrt(m1));  /* K(m) up to O(m1 K) (DLMF 19.12.1) */
    double w = remainder(u, 4.0*quarter);       /* sn, cn have period 4K */
    const double snSign = (w < 0.0 ? -1.0 : 1.0);
    double cnSign = 1.0;
    RigidJacobi f;
    w = fabs(w);
    if (w > quarter) {  /* sn(2K - w) = sn(w), cn(2K - w) = -cn(w), dn(2K - w) = dn(w) */
        w = 2.0*quarter - w;
        cnSign = -1.0;
    }
    if (w <= 0.5*quarter)
        rigidJacobiExpansionNearOne(w, m1, &f);
    else {
        RigidJacobi v;
        const double kc = sqrt(m1);
        rigidJacobiExpansionNearOne(quarter - w, m1, &v);
        f.sn = v.cn/v.dn;
        f.cn = kc*v.sn/v.dn;
        f.dn = kc/v.dn;
    }
    result->sn = snSign*f.sn;
    result->cn = cnSign*f.cn;
    result->dn = f.dn;
}

/* The most levels of the descending Gauss transformation; the moduli fall quadratically, so that
 * even m1 = 1e-32 needs only about 8 levels to reach k < 1e-9. */
enum { RigidMaxGaussLevels = 40 };

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
 * double the rounding error of cn at each level, so rigidJacobiEllipticNearOne() takes over there.
 * Contract: u finite, 0 <= m <= 1, 0 <= m1 <= 1 and m1 = 1 - m to the caller's precision.
 */
RIGID_FUNCTION void rigidJacobiElliptic(double u, double m, double m1, RigidJacobi* result) {
    double modulus[RigidMaxGaussLevels + 1], complement[RigidMaxGaussLevels + 1];
    double z = u, s, c, d, radius;
    int levels = 0, n;
    if (m == 0.0) {
        result->sn = sin(u);
        result->cn = cos(u);
        result->dn = 1.0;
        return;
    }
    if (m1 == 0.0) {
        result->sn = tanh(u);
        result->cn = 1.0/cosh(u);
        result->dn = result->cn;
        return;
    }
    if (m1 < 1e-32) {
        rigidJacobiEllipticNearOne(u, m1, result);
        return;
    }
    modulus[0] = sqrt(m);
    complement[0] = sqrt(m1);
    while (modulus[levels] > 1e-9 && levels < RigidMaxGaussLevels) {
        const double kc = complement[levels];
        modulus[levels + 1] = (1.0 - kc)/(1.0 + kc);
        complement[levels + 1] = 2.0*sqrt(kc)/(1.0 + kc);
        z /= 1.0 + modulus[levels + 1];
        levels++;
    }
    /* K(m_N) = (pi/2)(1 + m_N/4 + O(m_N^2)) (DLMF 19.5.1). */
    z /= 1.0 + 0.25*modulus[levels]*modulus[levels];
    s = sin(z);
    c = cos(z);
    d = sqrt(1.0 - modulus[levels]*modulus[levels]*s*s);
    for (n = levels; n > 0; n--) {
        const double k = modulus[n];
        const double denominator = 1.0 + k*s*s;
        const double nextS = (1.0 + k)*s/denominator;
        c = c*d/denominator;
        s = nextS;
        d = sqrt(complement[n - 1]*complement[n - 1] + modulus[n - 1]*modulus[n - 1]*c*c);
    }
    /* Put (sn, cn) back on the unit circle; a common factor keeps the relative accuracy of each. */
    radius = sqrt(s*s + c*c);
    result->sn = s/radius;
    result->cn = c/radius;
    result->dn = sqrt(m1 + m*result->cn*result->cn);
}

#endif /* OPENMMRIGID_CORE_ELLIPTIC_H_ */
