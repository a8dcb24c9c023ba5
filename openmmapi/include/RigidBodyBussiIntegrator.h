#ifndef OPENMMRIGID_RIGIDBODYBUSSIINTEGRATOR_H_
#define OPENMMRIGID_RIGIDBODYBUSSIINTEGRATOR_H_

#include "RigidBodyIntegrator.h"
#include "internal/windowsExportRigid.h"
#include <vector>

namespace OpenMMRigid {

/**
 * RigidBodyIntegrator with a thermostat, for constant temperature: after every step the velocities of
 * all bodies (linear and angular) and free particles are scaled by one common factor, which samples the
 * kinetic energy from the exact solution over one step of the stochastic velocity rescaling of G. Bussi,
 * D. Donadio and M. Parrinello, J. Chem. Phys. 126, 014101 (2007), eq. (A7). The system samples the
 * canonical ensemble; the total energy minus the heat (getHeat()) is Bussi's effective energy,
 * conserved up to the integration error. The thermostat is global: it does not perturb the dynamics of
 * any one molecule, so time correlation functions keep their constant-energy form.
 *
 * The velocities it rescales, and reports, are on-step: the temperature of their total kinetic energy
 * reads the bath's at any step size, by construction. How that energy divides between translation and
 * rotation is the dynamics': for rigid water at 6 to 8 fs the on-step rotation reads cold and the
 * translation as much warm (docs/validation/thermostats.md gives the measurements).
 */
class OPENMM_EXPORT_RIGID RigidBodyBussiIntegrator : public RigidBodyIntegrator {
public:
    /**
     * Create a RigidBodyBussiIntegrator whose bodies are the rigid constraint clusters of the System.
     *
     * @param temperature    the temperature of the heat bath, measured in Kelvin
     * @param collisionTime  tau, the relaxation time of the kinetic energy, measured in ps
     * @param stepSize       the step size with which to integrate the system, measured in ps
     */
    RigidBodyBussiIntegrator(double temperature, double collisionTime, double stepSize);
    /**
     * Create a RigidBodyBussiIntegrator with explicitly chosen bodies (see RigidBodyIntegrator).
     *
     * @param temperature    the temperature of the heat bath, measured in Kelvin
     * @param collisionTime  tau, the relaxation time of the kinetic energy, measured in ps
     * @param stepSize       the step size with which to integrate the system, measured in ps
     * @param bodies         the particle indices of each body
     */
    RigidBodyBussiIntegrator(double temperature, double collisionTime, double stepSize, const std::vector<std::vector<int> >& bodies);
    /**
     * Get the temperature of the heat bath.
     *
     * @return the temperature, measured in Kelvin
     */
    double getTemperature() const {
        return bath.temperature;
    }
    /**
     * Set the temperature of the heat bath. It may be changed between steps.
     *
     * @param temperature  the temperature, measured in Kelvin (0 damps the motion)
     * @throws OpenMMException if the temperature is negative or not finite
     */
    void setTemperature(double temperature);
    /**
     * Get the collision time tau: the relaxation time of the kinetic energy.
     *
     * @return the collision time, measured in ps
     */
    double getCollisionTime() const {
        return bath.collisionTime;
    }
    /**
     * Set the collision time tau: the relaxation time of the kinetic energy.
     *
     * @param collisionTime  the collision time, measured in ps
     * @throws OpenMMException if the collision time is not positive and finite
     */
    void setCollisionTime(double collisionTime);
    /** Get the random number seed (0: a new one for every Context). See setRandomNumberSeed(). */
    int getRandomNumberSeed() const {
        return randomNumberSeed;
    }
    /**
     * Set the random number seed, read when a Context is created. With the same seed the Reference and
     * CPU platforms give the same trajectory, with any number of threads.
     *
     * @param seed  the seed; 0 (the default) picks a new seed for every Context
     */
    void setRandomNumberSeed(int seed) {
        randomNumberSeed = seed;
    }
protected:
    int getRequestedSeed() const {
        return randomNumberSeed;
    }
    const BussiBath* getBath() const {
        return &bath;
    }
private:
    BussiBath bath;
    int randomNumberSeed;
};

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_RIGIDBODYBUSSIINTEGRATOR_H_*/
