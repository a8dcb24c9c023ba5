#ifndef OPENMMRIGID_RIGIDBODYSYSTEM_H_
#define OPENMMRIGID_RIGIDBODYSYSTEM_H_

#include "internal/windowsExportRigid.h"
#include "numerics/Matrix3.h"
#include "numerics/RigidCore.h"
#include "openmm/System.h"
#include "openmm/Vec3.h"
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace OpenMMRigid {

/**
 * The periodic box and the largest plausible drift at one moment: what a fit needs to assemble a body
 * split by the boundary, and what a drift needs to tell a blow-up from a step.
 */
struct StepGeometry {
    /** Whether the System is periodic; box holds OpenMM's reduced box vectors (nm) if it is. */
    bool periodic = false;
    OpenMM::Vec3 box[3];
    /** The largest distance a body or free particle may move in one drift, in nm (infinity for none). */
    double displacementLimit;
    /** What displacementLimit is, for the message (a string literal). */
    const char* displacementLimitName = "no limit";
    StepGeometry();
};

/**
 * The body topology of a Context: the partition of its System's particles into rigid bodies, free
 * (flexible) particles and massless virtual sites, with the constraints that remain among free
 * particles, and each body's shape. Built once per Context, as flat arrays that any platform can
 * copy as they are: body b's particles are getParticles()[getBodyStart(b)] to
 * getParticles()[getBodyStart(b + 1) - 1], and getBodyCoordinates() is parallel to getParticles().
 *
 * A body held rigid by constraints has its shape from the start. An explicit body takes its shape
 * once, from the first positions that give it one (captureShapes()); the handedness of a shape built
 * from distances alone is settled once, by the first fit (settleHandedness()). After that nothing
 * changes: every platform reads the same shapes.
 *
 * Every inconsistency (a particle in two bodies, a massless or virtual-site body member, a
 * constraint between a body and anything else) is an OpenMMException that names the integrator's
 * class, the body and the particle.
 */
/**
 * Which bodies a stage of a step moves, with multiple time steps (RigidBodySystem::setFastBodies()):
 * every body, the bodies a fast force reaches, or those it does not (which drift once over each drift
 * of the outermost level, since free drifts compose). The free particles move with AllBodies and
 * FastBodies.
 */
enum BodySet {
    AllBodies = 0,
    FastBodies = 1,
    SlowBodies = 2
};

class OPENMM_EXPORT_RIGID RigidBodySystem {
public:
    /**
     * @param system          the System
     * @param explicitBodies  the bodies given to the integrator, or empty to find them from the constraints
     * @param useExplicit     whether explicitBodies is the list of bodies (it may legitimately be empty)
     * @param className       the class of the integrator the user made, which every message names
     * @param minimumMoment   every nonzero principal moment below this (amu nm^2) is raised to it in the dynamics (0: none)
     */
    RigidBodySystem(const OpenMM::System& system, const std::vector<std::vector<int> >& explicitBodies, bool useExplicit,
                    const std::string& className, double minimumMoment = 0.0);
    /**
     * How far from a line, in nm, a body's particles may lie for the body to be linear: a body whose
     * particles are all within this distance of its axis of least moment, and within 1 % of its reach
     * along that axis, is put on the axis exactly when it takes its shape. 0.002 nm covers coordinates
     * rounded to 0.001 nm (a .gro file; a PDB file's 1e-4 nm by far), and straightens a bend of at
     * most about a degree in a triatomic molecule; a genuinely bent body lies farther off.
     */
    static constexpr double LinearTolerance = 0.002;
    /**
     * A constraint between two particles of one body (implied by its rigidity, checked against its
     * shape): its index in the System, the positions of its particles in the body's list, its length.
     */
    struct InternalConstraint {
        int index, first, second;
        double distance;
    };
    int getNumBodies() const {
        return bodyMass.size();
    }
    /** Where body b's particles start in getParticles(); getBodyStart(getNumBodies()) is the total. */
    int getBodyStart(int b) const {
        return bodyStart[b];
    }
    int getBodySize(int b) const {
        return bodyStart[b + 1] - bodyStart[b];
    }
    /** The particles of every body, body after body. */
    const std::vector<int>& getParticles() const {
        return particles;
    }
    /** The particles of body b (getBodySize(b) of them). */
    const int* getBodyParticles(int b) const {
        return &particles[bodyStart[b]];
    }
    /** The position of each body particle in its body's principal-axis frame, centre of mass at the origin (parallel to getParticles()). */
    const std::vector<Vector3>& getBodyCoordinates() const {
        return bodyCoordinates;
    }
    /** The body-frame coordinates of body b's particles. */
    const Vector3* getBodyCoordinates(int b) const {
        return &bodyCoordinates[bodyStart[b]];
    }
    double getBodyMass(int b) const {
        return bodyMass[b];
    }
    /**
     * The principal moments of inertia of body b, ascending, in amu nm^2 (zero for a point, the first
     * zero for a line), as the dynamics uses them: those rigidClassifyMoments() found equal are equal,
     * and those below the minimum moment are raised to it.
     */
    const double* getMoments(int b) const {
        return shapes[b].moments;
    }
    /** The principal moments of body b's particle masses (classified as getMoments(), but never raised), in the same axes. */
    const double* getMassMoments(int b) const {
        return massMoments[b].moments;
    }
    /**
     * For each principal axis of body b, getMoments(b)[k] / getMassMoments(b)[k] (1 on an axis of zero
     * moment): what rigidRaiseAngularMomentum() takes from the particles' angular momentum to the body's.
     */
    const double* getInertiaScale(int b) const {
        return &inertiaScale[3*b];
    }
    /** Whether any body's moments were raised (some getInertiaScale() is not 1). */
    bool hasRaisedMoments() const;
    /** Body b's kind (a RigidKind). */
    int getKind(int b) const {
        return shapes[b].kind;
    }
    /** Body b's moments with their kind, as the rotor of the numerics core takes them. */
    const RigidShape& getShape(int b) const {
        return shapes[b];
    }
    /** Whether body b has its shape (coordinates, moments, kind). */
    bool isShapeKnown(int b) const {
        return shapeKnown[b] != 0;
    }
    /** Whether every body has its shape. */
    bool allShapesKnown() const;
    /** Whether body b's shape came from distances alone, so that the first fit chooses between it and its mirror image. */
    bool isHandednessOpen(int b) const {
        return handednessOpen[b] != 0;
    }
    /** Keep body b's shape (mirror false) or replace it by its mirror image (z -> -z); either way it is settled. */
    void settleHandedness(int b, bool mirror);
    /**
     * Give every body that has no shape yet the one it has in these positions. Those the positions
     * cannot shape (non-finite, or every particle at one point) wait for later positions, or, if
     * strict, are an OpenMMException saying what is wrong. The constraints inside a body are applied to
     * its positions first where any is off by more than constraintTolerance (relative), so the shape
     * satisfies them (applyInternalConstraints()).
     */
    void captureShapes(const std::vector<OpenMM::Vec3>& positions, const StepGeometry& geometry, bool strict,
                       double constraintTolerance);
    /**
     * Whether these positions can give body b a shape (finite, not all at one point); if not and
     * strict, an OpenMMException saying which it is.
     */
    bool canShape(int b, const std::vector<OpenMM::Vec3>& positions, const StepGeometry& geometry, bool strict) const;
    /**
     * The positions of body b's particles, whole: the first particle where it is, and each other at
     * the periodic image nearest a neighbour already placed, along a tree that joins every particle
     * to the body by its shortest links (a minimum spanning tree: of the body's own shape once it has
     * one, of the minimum-image distances in these positions before), so that a molecule split by the
     * boundary is whole however far it reaches from its first particle. A particle already at the
     * image nearest its neighbour keeps its coordinates bit for bit. A body that has a link as long as
     * half the box's smallest width cannot be placed unambiguously: an OpenMMException names it.
     *
     * @param whole  on exit, getBodySize(b) positions in the body's order
     */
    void assemble(int b, const std::vector<OpenMM::Vec3>& positions, const StepGeometry& geometry, OpenMM::Vec3* whole) const;
    /** The centre of mass sum_i m_i x_i / M of body b, with x_i = values[i] in the body's order. */
    Vector3 centreOfMass(int b, const OpenMM::Vec3* values) const;
    /** centreOfMass(b, values), with each x_i's offset from it in offsets (resized to the body's size). */
    Vector3 centreOfMass(int b, const OpenMM::Vec3* values, std::vector<Vector3>& offsets) const;
    /** The centre of mass of body b with x_i = values[particle i] (e.g. the velocity of the centre of mass). */
    Vector3 centreOfMass(int b, const std::vector<OpenMM::Vec3>& values) const;
    /** The massive particles in no body. */
    const std::vector<int>& getFreeParticles() const {
        return freeParticles;
    }
    /**
     * Sort the bodies into fast ones (a particle of which the fast forces reach: `reached`, per particle,
     * from particlesReachedBy()) and slow ones, for the stages of multiple time steps (getBodySet()).
     * Before it every body is fast.
     */
    void setFastBodies(const std::vector<char>& reached);
    /** The bodies of a set, by index, ascending (AllBodies: 0 to getNumBodies() - 1). */
    const std::vector<int>& getBodySet(BodySet set) const {
        return bodySets[set];
    }
    /** A copy of the System's particles with only the constraints among free particles, or null if there are none. */
    const OpenMM::System* getFreeConstraintSystem() const {
        return freeConstraints.get();
    }
    /** The mass of every particle of the System (the one copy the plugin keeps). */
    const std::vector<double>& getMasses() const {
        return masses;
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
    /**
     * Degrees of freedom as the integrator moves the system (see RigidBodyIntegratorBase::getNumDegreesOfFreedom()).
     * Every body must have its shape (allShapesKnown()).
     */
    int getNumDegreesOfFreedom() const;
    /** Throw an OpenMMException naming the integrator, the particle and its body unless all three components of v are finite. */
    void requireFinite(const OpenMM::Vec3& v, const char* quantity, int particle, int body) const;
private:
    /** Add a body with these particles (checked against the System by checkBody()). */
    void addBody(const std::vector<int>& members);
    void findConstraintBodies(const OpenMM::System& system, std::vector<std::vector<double> >& pairDistances);
    void checkBody(const OpenMM::System& system, int index);
    /** Give body b the shape of the distances between each pair of its particles (n x n, row-major). */
    void shapeFromDistances(int b, const std::vector<double>& pairDistances);
    /** Give body b the shape it has in the positions; false (or, if strict, an exception) if they cannot give one. */
    bool shapeBody(int b, const std::vector<OpenMM::Vec3>& positions, const StepGeometry& geometry, bool strict,
                   double constraintTolerance);
    /**
     * Apply body b's internal constraints to its assembled positions (SHAKE) unless all hold within the
     * tolerance (relative); throw if that cannot be done.
     */
    void applyInternalConstraints(int b, std::vector<OpenMM::Vec3>& whole, double tolerance) const;
    /** Set body b's shape from coordinates about its centre of mass (any orientation): principal axes, moments, kind. */
    void setShape(int b, const std::vector<Vector3>& centred);
    /**
     * The order in which body b's particles are placed and the neighbour each is placed next to
     * (positions in the body's list; the first particle has none): a minimum spanning tree, grown from
     * the first particle, of the distance between particles i and j that distance(i, j) gives.
     * Returns the longest link.
     */
    double spanningTree(int b, const std::function<double(int, int)>& distance, int* order, int* neighbour) const;
    std::string className;
    std::vector<int> bodyStart, particles;
    std::vector<Vector3> bodyCoordinates;
    /** Parallel to particles: body b's particles in the order assemble() places them, and the neighbour each is placed at (-1 for the first). */
    std::vector<int> assemblyOrder, assemblyNeighbour;
    /** The longest link of each body's assembly tree, in nm (0 before it has its shape, or for a single particle). */
    std::vector<double> longestLink;
    std::vector<double> bodyMass;
    /** The moments of each body as the dynamics uses them (raised to minimumMoment), and those of its particles' masses. */
    std::vector<RigidShape> shapes, massMoments;
    /** 3 per body: getInertiaScale(). */
    std::vector<double> inertiaScale;
    double minimumMoment;
    std::vector<char> shapeKnown, handednessOpen;
    std::vector<std::vector<InternalConstraint> > internalConstraints;
    std::vector<int> freeParticles, bodyOfParticle;
    std::vector<double> masses;
    std::unique_ptr<OpenMM::System> freeConstraints;
    int numFreeConstraints = 0;
    bool removesCenterOfMassMotion = false;
    double largestCutoff;
    std::vector<int> bodySets[3];
};

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_RIGIDBODYSYSTEM_H_*/
