#include "internal/RigidBodyDynamics.h"
#include "numerics/FreeRotor.h"
#include "numerics/NoSquish.h"
#include "numerics/Philox.h"
#include "numerics/SymmetricEigen.h"
#include "openmm/OpenMMException.h"
#include "openmm/internal/ThreadPool.h"
#include "openmm/reference/ReferenceConstraints.h"
#include <cmath>
#include <limits>
#include <mutex>
#include <sstream>
#include <string>

using namespace OpenMM;
using namespace std;

namespace OpenMMRigid {

namespace {

Vector3 toVector(const Vec3& v) {
    return {v[0], v[1], v[2]};
}

Vec3 toVec3(const Vector3& v) {
    return Vec3(v[0], v[1], v[2]);
}

/** The body-frame angular velocity I^-1 L; a zero moment (the axis of a linear body) carries none. */
Vector3 bodyAngularVelocity(const RigidBody& body, const Vector3& bodyAngularMomentum) {
    Vector3 omega;
    for (int k = 0; k < 3; k++)
        omega[k] = (body.moments[k] > 0.0 ? bodyAngularMomentum[k]/body.moments[k] : 0.0);
    return omega;
}

bool isFinite(const Vec3& v) {
    return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]);
}

/** Throw, naming the integrator, particle and body, unless all three components are finite. */
void requireFinite(const string& className, const Vec3& v, const char* quantity, int particle, int body) {
    if (!isFinite(v))
        throw OpenMMException(className + ": particle " + to_string(particle) + " of body " + to_string(body) +
                " has a non-finite " + quantity);
}

/** One Newton-Schulz step towards the nearest rotation, A (3 - A^T A) / 2: removes the rounding drift. */
void reorthonormalize(Matrix3& a) {
    Matrix3 g = multiplyTransposed(a, a);
    Matrix3 correction;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            correction[i][j] = 0.5*((i == j ? 3.0 : 0.0) - g[i][j]);
    a = multiply(a, correction);
}

} // namespace

RigidBodyDynamics::RigidBodyDynamics(RigidBodySystem& system) : system(system), periodic(false),
        displacementLimit(numeric_limits<double>::infinity()), displacementLimitName("no limit"), threads(NULL) {
    states.resize(system.getBodies().size());
    const vector<double>& masses = system.getMasses();
    inverseMasses.resize(masses.size());
    for (size_t i = 0; i < masses.size(); i++)
        inverseMasses[i] = (masses[i] == 0.0 ? 0.0 : 1.0/masses[i]);
    if (system.getFreeConstraintSystem() != NULL)
        constraints.reset(new ReferenceConstraints(*system.getFreeConstraintSystem()));
}

RigidBodyDynamics::~RigidBodyDynamics() {
}

void RigidBodyDynamics::setThreadPool(ThreadPool* pool) {
    threads = pool;
}

void RigidBodyDynamics::forEachBody(const function<void(int)>& task) {
    // An exception must not escape a worker thread: the first one is kept and rethrown here.
    const int numBodies = states.size();
    mutex errorLock;
    string error;
    auto guarded = [&](int b) {
        try {
            task(b);
        }
        catch (const exception& e) {
            lock_guard<mutex> lock(errorLock);
            if (error.empty())
                error = e.what();
        }
    };
    if (threads == NULL || threads->getNumThreads() < 2 || numBodies < 64) {
        for (int b = 0; b < numBodies; b++)
            guarded(b);
    }
    else {
        threads->execute([&](ThreadPool& pool, int thread) {
            int begin = (numBodies*(long long) thread)/pool.getNumThreads();
            int end = (numBodies*(long long) (thread + 1))/pool.getNumThreads();
            for (int b = begin; b < end; b++)
                guarded(b);
        });
        threads->waitForThreads();
    }
    if (!error.empty())
        throw OpenMMException(error);
}

void RigidBodyDynamics::setPeriodicBox(const Vec3* vectors) {
    periodic = (vectors != NULL);
    if (periodic)
        for (int k = 0; k < 3; k++)
            box[k] = vectors[k];
}

void RigidBodyDynamics::setDisplacementLimit(double limit, const char* description) {
    displacementLimit = limit;
    displacementLimitName = description;
}

void RigidBodyDynamics::assemble(const RigidBody& body, const vector<Vec3>& positions, vector<Vec3>& whole) const {
    // Each particle at the periodic image nearest the body's first particle (a body is far smaller
    // than half the box), so that a molecule split by the boundary in the positions given is whole.
    // The box is in OpenMM's reduced form: c, then b, then a removes each component in turn. A
    // particle already nearest keeps its coordinates bit for bit.
    const int n = body.particles.size();
    whole.resize(n);
    const Vec3& first = positions[body.particles[0]];
    for (int i = 0; i < n; i++) {
        Vec3 r = positions[body.particles[i]];
        if (periodic && i > 0) {
            for (int k = 2; k >= 0; k--) {
                double shift = round((r[k] - first[k])/box[k][k]);
                if (shift != 0.0)
                    r -= box[k]*shift;
            }
        }
        whole[i] = r;
    }
}

bool RigidBodyDynamics::shapeBody(int b, const vector<Vec3>& positions, bool strict) {
    RigidBody& body = system.getBodies()[b];
    const string& className = system.getClassName();
    const int n = body.particles.size();
    vector<Vec3> whole;
    assemble(body, positions, whole);
    bool finite = true, spread = (n == 1);
    for (int i = 0; i < n; i++) {
        finite = finite && isFinite(whole[i]);
        spread = spread || whole[i] != whole[0];
    }
    if (!finite || !spread) {
        if (!strict)
            return false;
        for (int i = 0; i < n; i++)
            requireFinite(className, whole[i], "position", body.particles[i], b);
        throw OpenMMException(className + ": the particles of body " + to_string(b) + " all sit at one point; "
                "an explicit body takes its shape from the positions, so set them before using the body");
    }
    // A constraint inside the body is implied by its rigidity; one the shape contradicts is a mistake
    // in the System or the positions, not something to drop silently. 1 % allows for positions read
    // from a file with a few digits.
    for (const RigidBodySystem::InternalConstraint& constraint : system.getInternalConstraints(b)) {
        const Vec3 separation = whole[constraint.first] - whole[constraint.second];
        double distance = sqrt(separation.dot(separation));
        if (fabs(distance - constraint.distance) > 0.01*constraint.distance)
            throw OpenMMException(className + ": constraint " + to_string(constraint.index) + " holds particles " +
                    to_string(body.particles[constraint.first]) + " and " + to_string(body.particles[constraint.second]) +
                    " of body " + to_string(b) + " at " + to_string(constraint.distance) + " nm, but the positions that give "
                    "the body its shape put them " + to_string(distance) + " nm apart; remove the constraint or set positions "
                    "that satisfy it");
    }
    Vector3 center;
    vector<Vector3> centred;
    centre(body, whole, center, centred);
    body.setShape(centred);
    return true;
}

void RigidBodyDynamics::centre(const RigidBody& body, const vector<Vec3>& whole, Vector3& center, vector<Vector3>& centred) const {
    const int n = body.particles.size();
    center = {0.0, 0.0, 0.0};
    for (int i = 0; i < n; i++)
        for (int k = 0; k < 3; k++)
            center[k] += body.masses[i]*whole[i][k]/body.mass;
    centred.resize(n);
    for (int i = 0; i < n; i++)
        for (int k = 0; k < 3; k++)
            centred[i][k] = whole[i][k] - center[k];
}

void RigidBodyDynamics::captureShapes(const vector<Vec3>& positions) {
    shapeBodies(positions, false);
}

void RigidBodyDynamics::shapeBodies(const vector<Vec3>& positions, bool strict) {
    for (size_t b = 0; b < system.getBodies().size(); b++)
        if (!system.getBodies()[b].shapeKnown)
            shapeBody(b, positions, strict);
}

bool RigidBodyDynamics::allShapesKnown() const {
    for (const RigidBody& body : system.getBodies())
        if (!body.shapeKnown)
            return false;
    return true;
}

void RigidBodyDynamics::project(vector<Vec3>& positions, vector<Vec3>& velocities) {
    shapeBodies(positions, true);
    for (size_t b = 0; b < states.size(); b++)
        fitBody(b, positions, velocities);
    writtenVelocities = velocities;
}

void RigidBodyDynamics::fitBody(int index, vector<Vec3>& positions, vector<Vec3>& velocities) {
    RigidBody& body = system.getBodies()[index];
    BodyState& state = states[index];
    const string& className = system.getClassName();
    const int n = body.particles.size();
    vector<Vec3> whole;
    assemble(body, positions, whole);
    for (int i = 0; i < n; i++)
        requireFinite(className, whole[i], "position", body.particles[i], index);
    Vector3 center;
    vector<Vector3> centred;
    centre(body, whole, center, centred);
    Matrix3 rotation = identityMatrix();  // body to lab
    if (body.kind != RigidBody::Point) {
        double residual;
        rotation = bestFitRotation(body.bodyCoordinates, centred, body.masses, residual);
        if (body.handednessOpen) {
            vector<Vector3> mirrored = body.bodyCoordinates;
            for (Vector3& x : mirrored)
                x[2] = -x[2];
            double mirroredResidual;
            Matrix3 mirroredRotation = bestFitRotation(mirrored, centred, body.masses, mirroredResidual);
            if (mirroredResidual < residual) {
                body.bodyCoordinates = mirrored;
                rotation = mirroredRotation;
            }
            body.handednessOpen = false;
        }
    }
    state.center = center;
    state.attitude = transpose(rotation);
    for (int i = 0; i < n; i++)
        positions[body.particles[i]] = toVec3(center) + toVec3(multiply(rotation, body.bodyCoordinates[i]));
    projectBodyVelocities(index, velocities);
}

void RigidBodyDynamics::projectBodyVelocities(int index, vector<Vec3>& velocities) {
    // The rigid motion with the linear and angular momentum of the velocities about the fitted shape.
    const RigidBody& body = system.getBodies()[index];
    BodyState& state = states[index];
    const int n = body.particles.size();
    Vector3 velocity = {0.0, 0.0, 0.0};
    for (int i = 0; i < n; i++) {
        const Vec3& v = velocities[body.particles[i]];
        requireFinite(system.getClassName(), v, "velocity", body.particles[i], index);
        for (int k = 0; k < 3; k++)
            velocity[k] += body.masses[i]*v[k]/body.mass;
    }
    state.velocity = velocity;
    const Matrix3 rotation = transpose(state.attitude);
    Vector3 angularMomentum = {0.0, 0.0, 0.0};
    vector<Vector3> arms(n);
    for (int i = 0; i < n; i++) {
        arms[i] = multiply(rotation, body.bodyCoordinates[i]);
        Vector3 relative = toVector(velocities[body.particles[i]] - toVec3(velocity));
        Vector3 moment = cross(arms[i], relative);
        for (int k = 0; k < 3; k++)
            angularMomentum[k] += body.masses[i]*moment[k];
    }
    state.angularMomentum = angularMomentum;
    Vector3 omega = multiplyTransposed(state.attitude, bodyAngularVelocity(body, multiply(state.attitude, angularMomentum)));
    for (int i = 0; i < n; i++)
        velocities[body.particles[i]] = toVec3(velocity) + toVec3(cross(omega, arms[i]));
}

void RigidBodyDynamics::projectVelocities(vector<Vec3>& velocities) {
    for (size_t b = 0; b < states.size(); b++)
        projectBodyVelocities(b, velocities);
    writtenVelocities = velocities;
}

void RigidBodyDynamics::rotate(const RigidBody& body, BodyState& state, double dt, RigidBodyIntegratorBase::RotationMethod method) const {
    Vector3 bodyMomentum = multiply(state.attitude, state.angularMomentum);
    if (body.kind == RigidBody::Point)
        return;
    // A linear body's free motion is a uniform rotation about L, which both methods take exactly:
    // NO_SQUISH's turns about the perpendicular axes would move part of L onto the molecular axis,
    // where the body can carry none.
    if (method == RigidBodyIntegratorBase::NoSquish && body.kind != RigidBody::Linear)
        noSquishRotate(body.moments, dt, state.attitude, bodyMomentum);
    else {
        // The attitude is kept orthonormal here and the momenta were checked finite in kickAndDrift().
        Vector3 omega = bodyAngularVelocity(body, bodyMomentum);
        FreeRotor::advance(body.moments, omega, state.attitude, dt, false);
    }
    reorthonormalize(state.attitude);
}

void RigidBodyDynamics::refreshMomenta(int b, const vector<Vec3>& positions, const vector<Vec3>& velocities) {
    // Rebuilding the momenta from the particles at every step would not do: the few-ulp mismatch
    // between the moments and the body coordinates would then scale L by the same factor every
    // step, a slow systematic drift. So they are rebuilt only when the velocities were changed, and
    // the changed velocities are then recorded as seen: the later stages of the step must keep the
    // momenta their kicks made, not rebuild them again from velocities that are now out of date.
    const RigidBody& body = system.getBodies()[b];
    BodyState& state = states[b];
    const int n = body.particles.size();
    bool changed = false;
    for (int i = 0; i < n && !changed; i++)
        changed = (velocities[body.particles[i]] != writtenVelocities[body.particles[i]]);
    if (!changed)
        return;
    Vec3 momentum, angularMomentum;
    for (int i = 0; i < n; i++)
        momentum += velocities[body.particles[i]]*body.masses[i];
    Vec3 velocity = momentum/body.mass;
    for (int i = 0; i < n; i++) {
        int p = body.particles[i];
        angularMomentum += (positions[p] - toVec3(state.center)).cross(velocities[p] - velocity)*body.masses[i];
    }
    state.velocity = toVector(velocity);
    state.angularMomentum = toVector(angularMomentum);
    for (int i = 0; i < n; i++)
        writtenVelocities[body.particles[i]] = velocities[body.particles[i]];
}

void RigidBodyDynamics::forceAndTorque(const RigidBody& body, const BodyState& state, const vector<Vec3>& positions,
                                       const vector<Vec3>& forces, Vec3& force, Vec3& torque) const {
    force = torque = Vec3();
    for (size_t i = 0; i < body.particles.size(); i++) {
        int p = body.particles[i];
        force += forces[p];
        torque += (positions[p] - toVec3(state.center)).cross(forces[p]);
    }
}

void RigidBodyDynamics::driftBody(int b, double h, RigidBodyIntegratorBase::RotationMethod method, vector<Vec3>& positions) {
    const RigidBody& body = system.getBodies()[b];
    BodyState& state = states[b];
    for (int k = 0; k < 3; k++)
        state.center[k] += h*state.velocity[k];
    rotate(body, state, h, method);
    for (size_t i = 0; i < body.particles.size(); i++)
        positions[body.particles[i]] = toVec3(state.center) + toVec3(multiplyTransposed(state.attitude, body.bodyCoordinates[i]));
}

void RigidBodyDynamics::kickAndDrift(vector<Vec3>& positions, vector<Vec3>& velocities, const vector<Vec3>& forces,
                                     double kick, double drift, RigidBodyIntegratorBase::RotationMethod method,
                                     double constraintTolerance) {
    advance(positions, velocities, &forces, kick, drift, method, constraintTolerance);
}

void RigidBodyDynamics::drift(vector<Vec3>& positions, vector<Vec3>& velocities, double drift,
                              RigidBodyIntegratorBase::RotationMethod method, double constraintTolerance) {
    advance(positions, velocities, NULL, 0.0, drift, method, constraintTolerance);
}

void RigidBodyDynamics::advance(vector<Vec3>& positions, vector<Vec3>& velocities, const vector<Vec3>* forces,
                                double kick, double drift, RigidBodyIntegratorBase::RotationMethod method,
                                double constraintTolerance) {
    const vector<RigidBody>& bodies = system.getBodies();
    forEachBody([&](int b) {
        const RigidBody& body = bodies[b];
        BodyState& state = states[b];
        refreshMomenta(b, positions, velocities);
        if (forces != NULL) {
            Vec3 force, torque;
            forceAndTorque(body, state, positions, *forces, force, torque);
            Vec3 velocity = toVec3(state.velocity) + force*(kick/body.mass);
            Vec3 angularMomentum = toVec3(state.angularMomentum) + torque*kick;
            if (!(isfinite(velocity.dot(velocity)) && isfinite(angularMomentum.dot(angularMomentum))))
                throw OpenMMException(system.getClassName() + ": body " + to_string(b) + " has a non-finite velocity, force or "
                        "torque; the simulation is unstable (try a smaller step size)");
            state.velocity = toVector(velocity);
            state.angularMomentum = toVector(angularMomentum);
        }
        checkDisplacement("body", b, sqrt(state.velocity[0]*state.velocity[0] + state.velocity[1]*state.velocity[1] +
                                          state.velocity[2]*state.velocity[2])*fabs(drift), drift);
        driftBody(b, drift, method, positions);
    });
    const vector<int>& free = system.getFreeParticles();
    for (int p : free) {
        if (forces != NULL)
            velocities[p] += (*forces)[p]*(kick*inverseMasses[p]);
        checkDisplacement("particle", p, sqrt(velocities[p].dot(velocities[p]))*fabs(drift), drift);
    }
    if (constraints)
        previousPositions = positions;
    for (int p : free)
        positions[p] += velocities[p]*drift;
    if (constraints) {
        constraints->apply(previousPositions, positions, inverseMasses, constraintTolerance);
        for (int p : free)
            velocities[p] = (positions[p] - previousPositions[p])/drift;
    }
}

void RigidBodyDynamics::checkDisplacement(const char* what, int index, double distance, double drift) const {
    // Not "distance > limit": a NaN distance must stop the step too.
    if (distance <= displacementLimit)
        return;
    stringstream text;
    text << system.getClassName() << ": " << what << " " << index << " would move " << distance << " nm in one drift of " <<
            fabs(drift) << " ps, more than " << displacementLimitName << " (" << displacementLimit << " nm); the simulation "
            "is unstable (try a smaller step size, or minimize the energy first)";
    throw OpenMMException(text.str());
}

void RigidBodyDynamics::thermalize(vector<Vec3>& positions, vector<Vec3>& velocities, double c, double kT,
                                   uint64_t seed, uint64_t step, double constraintTolerance) {
    // The exact Ornstein-Uhlenbeck flow: the mean decays by c, and the variance goes from its
    // starting value s to c^2 s + (1 - c^2) m kT, so the canonical variance m kT stays fixed.
    const double noise = sqrt((1.0 - c*c)*kT);
    const vector<RigidBody>& bodies = system.getBodies();
    forEachBody([&](int b) {
        const RigidBody& body = bodies[b];
        BodyState& state = states[b];
        NormalStream normal(seed, b, step);
        const double velocityNoise = noise/sqrt(body.mass);
        for (int k = 0; k < 3; k++)
            state.velocity[k] = c*state.velocity[k] + velocityNoise*normal.next();
        // In the principal frame the rotational kinetic energy is sum L_k^2 / (2 I_k): each component
        // is an independent Gaussian of variance I_k kT (none along the axis of a linear body, I_0 = 0).
        // The deviates are drawn in the lab frame and turned into the body frame: a rotated isotropic
        // Gaussian is one, and the noise in the lab, A^T diag(sqrt(I_k)) A xi, is then the square
        // root of the lab inertia tensor applied to xi, whatever principal axes (signs, order of
        // equal moments, turn of a linear body about its axis) the body's shape was given. So a
        // trajectory does not depend on how or when the body was fitted (a checkpoint loaded into
        // a new Context continues it).
        Vector3 xi;
        for (int k = 0; k < 3; k++)
            xi[k] = normal.next();
        if (body.kind != RigidBody::Point) {
            Vector3 bodyMomentum = multiply(state.attitude, state.angularMomentum), bodyXi = multiply(state.attitude, xi);
            for (int k = 0; k < 3; k++)
                bodyMomentum[k] = c*bodyMomentum[k] + noise*sqrt(body.moments[k])*bodyXi[k];
            state.angularMomentum = multiplyTransposed(state.attitude, bodyMomentum);
        }
    });
    const vector<int>& free = system.getFreeParticles();
    const uint32_t firstStream = bodies.size();
    for (size_t i = 0; i < free.size(); i++) {
        int p = free[i];
        NormalStream normal(seed, firstStream + i, step);
        const double velocityNoise = noise*sqrt(inverseMasses[p]);
        for (int k = 0; k < 3; k++)
            velocities[p][k] = c*velocities[p][k] + velocityNoise*normal.next();
    }
    if (constraints)
        constraints->applyToVelocities(positions, velocities, inverseMasses, constraintTolerance);
}

void RigidBodyDynamics::scaleVelocities(vector<Vec3>& velocities, double alpha) {
    for (BodyState& state : states)
        for (int k = 0; k < 3; k++) {
            state.velocity[k] *= alpha;
            state.angularMomentum[k] *= alpha;
        }
    for (const RigidBody& body : system.getBodies())
        for (int p : body.particles)
            velocities[p] *= alpha;
    for (int p : system.getFreeParticles())
        velocities[p] *= alpha;
    writtenVelocities = velocities;
}

void RigidBodyDynamics::closingKick(vector<Vec3>& positions, vector<Vec3>& velocities, const vector<Vec3>& forces,
                                    double kick, double constraintTolerance) {
    const vector<RigidBody>& bodies = system.getBodies();
    forEachBody([&](int b) {
        const RigidBody& body = bodies[b];
        BodyState& state = states[b];
        Vec3 force, torque;
        forceAndTorque(body, state, positions, forces, force, torque);
        // (This rounds as kickAndDrift's kick, force*(kick/mass), does not; both are kept as they were
        // when the two were the halves of the Verlet step, so that its trajectories stay bit for bit.)
        for (int k = 0; k < 3; k++) {
            state.velocity[k] += kick*force[k]/body.mass;
            state.angularMomentum[k] += kick*torque[k];
        }
        Vector3 omega = multiplyTransposed(state.attitude,
                bodyAngularVelocity(body, multiply(state.attitude, state.angularMomentum)));
        for (size_t i = 0; i < body.particles.size(); i++) {
            int p = body.particles[i];
            velocities[p] = toVec3(state.velocity) + toVec3(omega).cross(positions[p] - toVec3(state.center));
        }
    });
    for (int p : system.getFreeParticles())
        velocities[p] += forces[p]*(kick*inverseMasses[p]);
    if (constraints)
        constraints->applyToVelocities(positions, velocities, inverseMasses, constraintTolerance);
    writtenVelocities = velocities;
}

void RigidBodyDynamics::computeKineticEnergies(const vector<Vec3>& velocities, double& translational, double& rotational) const {
    translational = 0.0;
    rotational = 0.0;
    for (const RigidBody& body : system.getBodies()) {
        Vec3 momentum;
        for (size_t i = 0; i < body.particles.size(); i++)
            momentum += velocities[body.particles[i]]*body.masses[i];
        Vec3 velocity = momentum/body.mass;
        translational += 0.5*body.mass*velocity.dot(velocity);
        for (size_t i = 0; i < body.particles.size(); i++) {
            Vec3 relative = velocities[body.particles[i]] - velocity;
            rotational += 0.5*body.masses[i]*relative.dot(relative);
        }
    }
    const vector<double>& masses = system.getMasses();
    for (int p : system.getFreeParticles())
        translational += 0.5*masses[p]*velocities[p].dot(velocities[p]);
}

} // namespace OpenMMRigid
