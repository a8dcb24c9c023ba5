#ifndef OPENMMRIGID_RIGIDBODYDYNAMICS_H_
#define OPENMMRIGID_RIGIDBODYDYNAMICS_H_

#include "RigidBodyIntegrator.h"
#include "internal/RigidBodySystem.h"
#include "internal/windowsExportRigid.h"
#include "numerics/Matrix3.h"
#include "openmm/Vec3.h"
#include <functional>
#include <memory>
#include <vector>

namespace OpenMM {
class ReferenceConstraintAlgorithm;
class ThreadPool;
}

namespace OpenMMRigid {

/**
 * The physics of one RigidBodyIntegrator step on plain arrays of positions, velocities and forces
 * (every platform's kernel extracts its arrays and calls this class). A step is split in two around
 * the force evaluation that the caller performs:
 *
 *   firstHalf():  for each body, V and L (lab frame) from the particle velocities, a half kick
 *                 V += F dt / 2M, L += tau dt / 2, the free drift R += V dt and the rotation of the
 *                 attitude (exact free rotor or NO_SQUISH), and the particles placed at R + A^T b;
 *                 free particles: half kick and drift, with their constraints applied to positions.
 *   secondHalf(): after the caller computed forces at the new positions, the second half kick, and
 *                 the rigid velocities v = V + omega x (r - R) written to the particles; free
 *                 particles: half kick and velocity constraints.
 *
 * Forces and torques are summed over the massive particles of each body only: the force on a virtual
 * site has already been distributed to its parents.
 */
class OPENMM_EXPORT_RIGID RigidBodyDynamics {
public:
    explicit RigidBodyDynamics(RigidBodySystem& system);
    ~RigidBodyDynamics();
    /**
     * Run the per-body work on these threads (the CPU platform's); null runs it serially.
     */
    void setThreadPool(OpenMM::ThreadPool* pool);
    /**
     * Fit every body to the positions (mass-weighted least squares, Horn's method), then replace the
     * body particles' positions by the rigid ones and their velocities by the rigid motion with the
     * same linear and angular momentum. Explicit bodies take their shape from the first positions.
     */
    void project(std::vector<OpenMM::Vec3>& positions, std::vector<OpenMM::Vec3>& velocities);
    void firstHalf(std::vector<OpenMM::Vec3>& positions, std::vector<OpenMM::Vec3>& velocities,
                   const std::vector<OpenMM::Vec3>& forces, double dt, RigidBodyIntegrator::RotationMethod method,
                   double constraintTolerance);
    void secondHalf(std::vector<OpenMM::Vec3>& positions, std::vector<OpenMM::Vec3>& velocities,
                    const std::vector<OpenMM::Vec3>& forces, double dt, double constraintTolerance);
    /**
     * Split the kinetic energy of the velocities: the translation of the bodies' centres plus the free
     * particles, and the rest of the bodies' kinetic energy (their rotation, for rigid velocities).
     */
    void computeKineticEnergies(const std::vector<OpenMM::Vec3>& velocities, double& translational, double& rotational) const;
private:
    struct BodyState {
        Vector3 center, velocity, angularMomentum;  // angular momentum in the lab frame
        Matrix3 attitude;                           // lab to body
    };
    void forEachBody(const std::function<void(int)>& task);
    /** Make sure every body has a shape, taking explicit bodies' shapes from these positions. */
    void ensureShapes(const std::vector<OpenMM::Vec3>& positions);
    void rotate(const RigidBody& body, BodyState& state, double dt, RigidBodyIntegrator::RotationMethod method) const;
    void fitBody(int index, std::vector<OpenMM::Vec3>& positions, std::vector<OpenMM::Vec3>& velocities);
    RigidBodySystem& system;
    std::vector<BodyState> states;
    std::vector<double> inverseMasses;
    std::vector<OpenMM::Vec3> previousPositions, writtenVelocities;
    std::unique_ptr<OpenMM::ReferenceConstraintAlgorithm> constraints;
    OpenMM::ThreadPool* threads;
};

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_RIGIDBODYDYNAMICS_H_*/
