#ifndef OPENMMRIGID_NUMERICS_STOCHASTICRESCALING_H_
#define OPENMMRIGID_NUMERICS_STOCHASTICRESCALING_H_

/*
 * The stochastic velocity rescaling thermostat of G. Bussi, D. Donadio and M. Parrinello, J. Chem.
 * Phys. 126, 014101 (2007): the kinetic energy K of N_f degrees of freedom follows the stochastic
 * differential equation (their eq. (7))
 *
 *     dK = (Kbar - K) dt/tau + 2 sqrt(K Kbar/(N_f tau)) dW,    Kbar = N_f kT/2,
 *
 * whose stationary distribution is the canonical one of K, and the velocities are scaled by
 * alpha = sqrt(K'/K). Over a time t the exact solution is (their eq. (A7)), with c = exp(-t/tau),
 *
 *     K' = c K + (1 - c) Kbar (R_1^2 + S)/N_f + 2 R_1 sqrt(c (1 - c) K Kbar/N_f),
 *
 * R_1 a standard normal deviate and S a chi-squared deviate with N_f - 1 degrees of freedom (the sum
 * of N_f - 1 more squared normals); alpha takes the sign of R_1 + sqrt(c N_f K/((1 - c) Kbar)) (their
 * eq. (A8)), which is negative only in the rare case that the scaling passes through zero.
 *
 * Accuracy: exact to rounding. The chi-squared deviate is a sum of squares for up to 32 degrees of
 * freedom and 2 Gamma(n/2) by the exact rejection method of G. Marsaglia and W. W. Tsang, ACM Trans.
 * Math. Softw. 26, 363 (2000) above that.
 */

#include "numerics/Philox.h"
#include <cmath>

namespace OpenMMRigid {

/** A chi-squared deviate with n degrees of freedom (n >= 0). */
inline double chiSquaredDeviate(int n, NormalStream& random) {
    if (n <= 32) {
        double sum = 0.0;
        for (int i = 0; i < n; i++) {
            double x = random.next();
            sum += x*x;
        }
        return sum;
    }
    // Marsaglia and Tsang (2000), Sec. 3: Gamma(a) for a >= 1 as d v with d = a - 1/3, v = (1 + c x)^3,
    // c = 1/sqrt(9 d), x standard normal, accepted when log u < x^2/2 + d - d v + d log v (with the
    // quick squeeze u < 1 - 0.0331 x^4 first). chi^2(n) = 2 Gamma(n/2).
    const double d = 0.5*n - 1.0/3.0, c = 1.0/std::sqrt(9.0*d);
    while (true) {
        double x = random.next(), v = 1.0 + c*x;
        if (v <= 0.0)
            continue;
        v = v*v*v;
        double u = random.uniform();
        if (u < 1.0 - 0.0331*x*x*x*x || std::log(u) < 0.5*x*x + d*(1.0 - v + std::log(v)))
            return 2.0*d*v;
    }
}

/**
 * The factor alpha by which the velocities are scaled in one step of the thermostat, and the new
 * kinetic energy alpha^2 K.
 *
 * @param kinetic        K, the kinetic energy now (> 0; for K = 0 nothing can be scaled and alpha is 1)
 * @param targetKinetic  Kbar = N_f kT/2 (>= 0; 0 damps: K' = c K)
 * @param dof            N_f, the number of degrees of freedom (> 0)
 * @param c              exp(-t/tau), in [0, 1]
 * @param random         the source of the deviates
 * @param newKinetic     set to K'
 */
inline double stochasticRescalingFactor(double kinetic, double targetKinetic, int dof, double c, NormalStream& random,
                                        double& newKinetic) {
    newKinetic = kinetic;
    if (!(kinetic > 0.0) || dof <= 0 || c >= 1.0)
        return 1.0;
    // Both deviates are drawn in every case, so that the stream is used alike whatever the values.
    const double r1 = random.next(), rest = chiSquaredDeviate(dof - 1, random);
    if (targetKinetic <= 0.0) {
        newKinetic = c*kinetic;
        return std::sqrt(c);
    }
    // Bussi, Donadio and Parrinello (2007), eq. (A7).
    newKinetic = c*kinetic + (1.0 - c)*targetKinetic*(r1*r1 + rest)/dof + 2.0*r1*std::sqrt(c*(1.0 - c)*kinetic*targetKinetic/dof);
    double alpha = std::sqrt(newKinetic/kinetic);
    // Eq. (A8): the sign of alpha.
    if (r1 + std::sqrt(c*dof*kinetic/((1.0 - c)*targetKinetic)) < 0.0)
        alpha = -alpha;
    return alpha;
}

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_NUMERICS_STOCHASTICRESCALING_H_*/
