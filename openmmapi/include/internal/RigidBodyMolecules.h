#ifndef OPENMMRIGID_RIGIDBODYMOLECULES_H_
#define OPENMMRIGID_RIGIDBODYMOLECULES_H_

#include "openmm/Force.h"
#include "openmm/internal/ContextImpl.h"
#include "openmm/internal/ForceImpl.h"
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace OpenMMRigid {

/**
 * Makes each explicit rigid body one molecule to OpenMM. OpenMM finds molecules from the System's
 * constraints and from the bonds its ForceImpls report (ForceImpl::getBondedParticles()), and an
 * explicit body may have neither: without this, a MonteCarloBarostat would scale the centre of each
 * atom of a body on its own, and getState(enforcePeriodicBox=true) (which the PDB and DCD reporters
 * use) would wrap a body atom by atom. The integrator adds this ForceImpl to its Context when it is
 * bound (install()); it reports a bond from each body's first particle to each other one, and adds
 * no force and no energy.
 */
class RigidBodyMoleculesImpl : public OpenMM::ForceImpl {
public:
    /**
     * Add a RigidBodyMoleculesImpl for these bodies to the context, and check that the context's
     * molecules now hold each body whole.
     *
     * @param context    the context the integrator is being bound to
     * @param bodies     the particle indices of each explicit body
     * @param className  the integrator's class, for the message if the molecules were already fixed
     */
    static void install(OpenMM::ContextImpl& context, const std::vector<std::vector<int> >& bodies, const std::string& className);
    explicit RigidBodyMoleculesImpl(const std::vector<std::vector<int> >& bodies);
    void initialize(OpenMM::ContextImpl& context) {
    }
    /** Changes nothing (ForceImpl's default would report the forces invalid at every step). */
    void updateContextState(OpenMM::ContextImpl& context, bool& forcesInvalid) {
    }
    const OpenMM::Force& getOwner() const {
        return owner;
    }
    double calcForcesAndEnergy(OpenMM::ContextImpl& context, bool includeForces, bool includeEnergy, int groups) {
        return 0.0;
    }
    std::map<std::string, double> getDefaultParameters() {
        return std::map<std::string, double>();
    }
    std::vector<std::string> getKernelNames() {
        return std::vector<std::string>();
    }
    std::vector<std::pair<int, int> > getBondedParticles() const {
        return bonds;
    }
private:
    /** The Force this ForceImpl stands for (OpenMM's interface requires one); it is in no System. */
    class Owner : public OpenMM::Force {
    public:
        explicit Owner(const std::vector<std::vector<int> >& bodies) : bodies(bodies) {
        }
        bool usesPeriodicBoundaryConditions() const {
            return false;
        }
    protected:
        OpenMM::ForceImpl* createImpl() const {
            return new RigidBodyMoleculesImpl(bodies);
        }
    private:
        std::vector<std::vector<int> > bodies;
    };
    Owner owner;
    std::vector<std::pair<int, int> > bonds;
};

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_RIGIDBODYMOLECULES_H_*/
