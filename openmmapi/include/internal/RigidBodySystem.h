#ifndef OPENMMRIGID_RIGIDBODYSYSTEM_H_
#define OPENMMRIGID_RIGIDBODYSYSTEM_H_

#include "internal/windowsExportRigid.h"
#include "numerics/Matrix3.h"
#include "openmm/System.h"
#include "openmm/Vec3.h"
#include <memory>
#include <string>
#include <vector>

namespace OpenMMRigid {

/**
 * The description of one rigid body: its particles and masses, and (once known) its shape in the
 * principal-axis frame with the centre of mass at the origin.
 */
struct OPENMM_EXPORT_RIGID RigidBody {
    enum Kind { Point = 0, Linear = 1, Spherical = 2, Symmetric = 3, Asymmetric = 4 };
    std::vector<int> particles;
    std::vector<double> masses;
    double mass = 0.0;
    /** Constraint distances of every pair when the constraints define the shape; empty otherwise. */
    std::vector<double> pairDistances;
    bool shapeKnown = false;
    /** The shape was built from distances alone, so its handedness is settled at the first fit. */
    bool handednessOpen = false;
    std::vector<Vector3> bodyCoordinates;
    Vector3 moments = {0.0, 0.0, 0.0};  // ascending
    Kind kind = Point;
    /** Set the shape from coordinates about the centre of mass (any orientation): principal axes, moments, kind. */
    void setShape(const std::vector<Vector3>& centred);
    static const char* kindName(Kind kind);
};

/**
 * The partition of a System's particles into rigid bodies, free (flexible) particles and massless
 * virtual sites, with the constraints that remain among free particles. Built once per Context;
 * every inconsistency (a particle in two bodies, a massless or virtual-site body member, a constraint
 * between a body and anything else) is an OpenMMException that names the body and particle.
 */
class OPENMM_EXPORT_RIGID RigidBodySystem {
public:
    /**
     * @param system          the System
     * @param explicitBodies  the bodies given to the integrator, or empty to find them from the constraints
     * @param useExplicit     whether explicitBodies is the list of bodies (it may legitimately be empty)
     * @param className       the class of the integrator the user made, which every message names
     */
    RigidBodySystem(const OpenMM::System& system, const std::vector<std::vector<int> >& explicitBodies, bool useExplicit,
                    const std::string& className);
    /**
     * A constraint between two particles of one body (implied by its rigidity, checked against its
     * shape): its index in the System, the positions of its particles in the body's list, its length.
     */
    struct InternalConstraint {
        int index, first, second;
        double distance;
    };
    std::vector<RigidBody>& getBodies() {
        return bodies;
    }
    const std::vector<RigidBody>& getBodies() const {
        return bodies;
    }
    /** The massive particles in no body. */
    const std::vector<int>& getFreeParticles() const {
        return freeParticles;
    }
    /** For each particle, the body it belongs to, or -1. */
    const std::vector<int>& getBodyOfParticle() const {
        return bodyOfParticle;
    }
    /** A copy of the System's particles with only the constraints among free particles, or null if there are none. */
    const OpenMM::System* getFreeConstraintSystem() const {
        return freeConstraints.get();
    }
    const std::vector<double>& getMasses() const {
        return masses;
    }
    /** The constraints inside body b (dropped from the dynamics; an explicit body's shape must agree with them). */
    const std::vector<InternalConstraint>& getInternalConstraints(int b) const {
        return internalConstraints[b];
    }
    /**
     * The largest cutoff of the System's NonbondedForce and CustomNonbondedForce objects, in nm
     * (infinity if none has one): no particle may move that far in one drift.
     */
    double getLargestCutoff() const {
        return largestCutoff;
    }
    /** "RigidBodyIntegrator" or "RigidBodyLangevinIntegrator": every message starts with it. */
    const std::string& getClassName() const {
        return className;
    }
    /** Degrees of freedom as the integrator moves the system (see RigidBodyIntegrator::getNumDegreesOfFreedom()). */
    int getNumDegreesOfFreedom() const;
private:
    void findConstraintBodies(const OpenMM::System& system);
    void checkBody(const OpenMM::System& system, int index);
    std::string className;
    std::vector<RigidBody> bodies;
    std::vector<std::vector<InternalConstraint> > internalConstraints;
    std::vector<int> freeParticles, bodyOfParticle;
    std::vector<double> masses;
    std::unique_ptr<OpenMM::System> freeConstraints;
    int numFreeConstraints = 0;
    bool removesCenterOfMassMotion = false;
    double largestCutoff;
};

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_RIGIDBODYSYSTEM_H_*/
