#ifndef OPENMMRIGID_NUMERICS_STOCHASTICRESCALING_H_
#define OPENMMRIGID_NUMERICS_STOCHASTICRESCALING_H_

/*
 * The stochastic velocity rescaling thermostat of G. Bussi, D. Donadio and M. Parrinello, J. Chem.
 * Phys. 126, 014101 (2007): the random deviates of one step, R_1 and S of their eq. (A7), drawn on
 * the host, and the factor alpha = sqrt(K'/K) from them. The arithmetic of eqs. (A7) and (A8) is the
 * numerics core's rigidStochasticRescaling() (core/CoreThermostat.h, which states the equations), so
 * that a device that holds the kinetic energy applies the same formula to deviates the host drew.
 *
 * Accuracy: exact to rounding. The chi-squared deviate is a sum of squares for up to 32 degrees of
 * freedom and 2 Gamma(n/2) by the exact rejection method of G. Marsaglia and W. W. Tsang, ACM Trans.
 * Math. Softw. 26, 363 (2000) above that.
 */

#include "numerics/Philox.h"
#include "numerics/RigidCore.h"
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
 * The deviates of one step of the thermostat, which do not depend on the kinetic energy: R_1, a
 * standard normal deviate, then S, a chi-squared deviate with N_f - 1 degrees of freedom (eq. (A7)),
 * in that order from `random`. They are drawn whenever the step can scale at all (dof > 0 and c < 1);
 * otherwise none is drawn and both are 0.
 *
 * @param dof     N_f, the number of degrees of freedom
 * @param c       exp(-t/tau)
 * @param random  the source of the deviates
 * @param r1      set to R_1
 * @param rest    set to S
 */
inline void stochasticRescalingDeviates(int dof, double c, NormalStream& random, double& r1, double& rest) {
    r1 = rest = 0.0;
    if (dof <= 0 || c >= 1.0)
        return;
    r1 = random.next();
    rest = chiSquaredDeviate(dof - 1, random);
}

/**
 * The factor alpha by which the velocities are scaled in one step of the thermostat, and the new
 * kinetic energy alpha^2 K: the deviates from stochasticRescalingDeviates(), then
 * rigidStochasticRescaling().
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
    double r1, rest;
    stochasticRescalingDeviates(dof, c, random, r1, rest);
    return rigidStochasticRescaling(kinetic, targetKinetic, dof, c, r1, rest, &newKinetic);
}

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_NUMERICS_STOCHASTICRESCALING_H_*/
