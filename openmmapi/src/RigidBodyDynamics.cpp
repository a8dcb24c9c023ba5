#include "internal/RigidBodyDynamics.h"
#include "internal/RotorLanes.h"
#include "numerics/Philox.h"
#include "numerics/RigidCore.h"
#include "numerics/SymmetricEigen.h"
#include "openmm/OpenMMException.h"
#include <algorithm>
#include <chrono>
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

/** The momentum of body b from its particles' angular momentum l (lab frame), its moments raised or not (rigidRaiseAngularMomentum). */
Vector3 bodyAngularMomentum(const RigidBodySystem& system, int b, const Matrix3& attitude, Vector3 l) {
    double a[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            a[i][j] = attitude[i][j];
    rigidRaiseAngularMomentum(a, system.getInertiaScale(b), l.data());
    return l;
}

/**
 * The angular momentum l = sum_i m_i (A^T b_i) x (v_i - V) of body b's particle velocities about the
 * body as it is fitted (attitude A, lab to body), with each arm A^T b_i put in arms if it is given.
 */
Vector3 particlesAngularMomentum(const RigidBodySystem& system, int b, const Matrix3& attitude, const vector<Vec3>& velocities,
                                 const Vec3& velocity, Vector3* arms) {
    const int n = system.getBodySize(b);
    const int* members = system.getBodyParticles(b);
    const vector<double>& masses = system.getMasses();
    const Matrix3 rotation = transpose(attitude);
    const Vector3* coordinates = system.getBodyCoordinates(b);
    Vector3 angularMomentum = {0.0, 0.0, 0.0};
    for (int i = 0; i < n; i++) {
        const Vector3 arm = multiply(rotation, coordinates[i]);
        if (arms != NULL)
            arms[i] = arm;
        Vector3 moment = cross(arm, toVector(velocities[members[i]] - velocity));
        for (int k = 0; k < 3; k++)
            angularMomentum[k] += masses[members[i]]*moment[k];
    }
    return angularMomentum;
}

} // namespace

RigidBodyDynamics::RigidBodyDynamics(RigidBodySystem& system, HostThreads* threads, HostConstraints* constraints) :
        system(system), threads(threads), constraints(constraints) {
    states.resize(system.getNumBodies());
    const vector<double>& masses = system.getMasses();
    inverseMasses.resize(masses.size());
    for (size_t i = 0; i < masses.size(); i++)
        inverseMasses[i] = (masses[i] == 0.0 ? 0.0 : 1.0/masses[i]);
}

void RigidBodyDynamics::requireConstraints() const {
    if (system.getFreeConstraintSystem() != NULL && constraints == NULL)
        throw OpenMMException(system.getClassName() + ": internal error: no solver for the constraints among free particles");
}

void RigidBodyDynamics::FirstError::keep(const char* message) {
    // An exception must not escape a worker thread: the first one is kept and rethrown by rethrow().
    lock_guard<mutex> lock(errorLock);
    if (error.empty())
        error = message;
}

void RigidBodyDynamics::FirstError::rethrow() const {
    if (!error.empty())
        throw OpenMMException(error);
}

ThreadedLoopChoice::ThreadedLoopChoice() : runs(0), nextProbe(0), probeInterval(FirstProbeInterval), preferThreads(false) {
    numSamples[0] = numSamples[1] = 0;
    nextSlot[0] = nextSlot[1] = 0;
}

bool ThreadedLoopChoice::useThreads() const {
    if (numSamples[0] == 0)
        return false;
    if (numSamples[1] == 0)
        return true;
    return (runs == nextProbe ? !preferThreads : preferThreads);
}

double ThreadedLoopChoice::median(bool threaded) const {
    const int k = (threaded ? 1 : 0), n = numSamples[k];
    double sorted[Window];
    std::copy(samples[k], samples[k] + n, sorted);
    std::sort(sorted, sorted + n);
    return (n % 2 == 1 ? sorted[n/2] : 0.5*(sorted[n/2 - 1] + sorted[n/2]));
}

void ThreadedLoopChoice::record(bool threaded, double seconds) {
    const int k = (threaded ? 1 : 0);
    const bool bothKnown = (numSamples[0] > 0 && numSamples[1] > 0);
    samples[k][nextSlot[k]] = seconds;
    nextSlot[k] = (nextSlot[k] + 1) % Window;
    numSamples[k] = min(numSamples[k] + 1, Window);
    runs++;
    if (!bothKnown) {
        if (numSamples[0] > 0 && numSamples[1] > 0) {
            preferThreads = (median(true) < median(false));
            nextProbe = runs + probeInterval;
        }
        return;
    }
    if (threaded != preferThreads) {
        // A probe: faster than the preferred way's recent runs, it becomes the preferred way.
        if (seconds < median(preferThreads)) {
            preferThreads = threaded;
            probeInterval = FirstProbeInterval;
        }
        else
            probeInterval = min(2*probeInterval, LastProbeInterval);
        nextProbe = runs + probeInterval;
    }
}

void RigidBodyDynamics::forEachBody(HostLoop loop, const function<void(int)>& task) {
    FirstError error;
    forEachRange(loop, states.size(), [&](int, int begin, int end) {
        for (int b = begin; b < end; b++)
            error.guard([&]() { task(b); });
    });
    error.rethrow();
}

void RigidBodyDynamics::forEachBodyGroup(HostLoop loop, int count, int size, const function<void(int begin, int end, FirstError& error)>& task) {
    FirstError error;
    forEachRange(loop, count, [&](int, int begin, int end) {
        for (int first = begin; first < end; first += size)
            task(first, min(end, first + size), error);
    });
    error.rethrow();
}

// Below these counts a loop runs serially without asking its ThreadedLoopChoice: 64 bodies of the
// cheapest stage take a few us, 4096 particles about 10 us to copy, less than waking any pool's
// threads and waiting for them.
static const int MinimumThreadedBodies = 64;
static const int MinimumThreadedParticles = 4096;

void RigidBodyDynamics::forEachRange(HostLoop loop, int count, const function<void(int thread, int begin, int end)>& task) const {
    const int minimum = (loop == CopyLoop || loop == CompareLoop ? MinimumThreadedParticles : MinimumThreadedBodies);
    if (threads == NULL || threads->getNumThreads() < 2 || count < minimum) {
        task(0, 0, count);
        return;
    }
    ThreadedLoopChoice& choice = loopChoices[loop];
    const bool threaded = choice.useThreads();
    const auto start = chrono::steady_clock::now();
    if (threaded) {
        const int numThreads = threads->getNumThreads();
        threads->execute([&](int thread) {
            task(thread, (count*(long long) thread)/numThreads, (count*(long long) (thread + 1))/numThreads);
        });
    }
    else
        task(0, 0, count);
    choice.record(threaded, chrono::duration<double>(chrono::steady_clock::now() - start).count());
}

void RigidBodyDynamics::copyParticleArray(const vector<Vec3>& from, vector<Vec3>& to) const {
    to.resize(from.size());
    forEachRange(CopyLoop, from.size(), [&](int, int begin, int end) {
        std::copy(from.begin() + begin, from.begin() + end, to.begin() + begin);
    });
}

bool RigidBodyDynamics::particleArraysEqual(const vector<Vec3>& a, const vector<Vec3>& b) const {
    if (a.size() != b.size())
        return false;
    const int maxThreads = (threads == NULL ? 1 : max(1, threads->getNumThreads()));
    vector<char> equal(maxThreads, 1);
    forEachRange(CompareLoop, a.size(), [&](int thread, int begin, int end) {
        equal[thread] = std::equal(a.begin() + begin, a.begin() + end, b.begin() + begin);
    });
    return std::find(equal.begin(), equal.end(), 0) == equal.end();
}

void RigidBodyDynamics::setGeometry(const StepGeometry& newGeometry) {
    geometry = newGeometry;
}

Vector3 RigidBodyDynamics::bodyAngularVelocity(int b, const Vector3& bodyAngularMomentum) const {
    Vector3 omega;
    rigidAngularVelocity(system.getMoments(b), bodyAngularMomentum.data(), omega.data());
    return omega;
}

void RigidBodyDynamics::project(vector<Vec3>& positions, vector<Vec3>& velocities) {
    for (size_t b = 0; b < states.size(); b++)
        fitBody(b, positions, velocities);
    writtenVelocities = velocities;
}

void RigidBodyDynamics::fitBody(int b, vector<Vec3>& positions, vector<Vec3>& velocities) {
    BodyState& state = states[b];
    const int n = system.getBodySize(b);
    const int* members = system.getBodyParticles(b);
    if (!system.isShapeKnown(b))
        throw OpenMMException(system.getClassName() + ": internal error: body " + to_string(b) + " is fitted before it has a shape");
    whole.resize(n);
    system.assemble(b, positions, geometry, whole.data());
    for (int i = 0; i < n; i++)
        system.requireFinite(whole[i], "position", members[i], b);
    const Vector3 center = system.centreOfMass(b, whole.data(), centred);
    Matrix3 rotation = identityMatrix();  // body to lab
    if (system.getKind(b) != RigidKindPoint) {
        shape.assign(system.getBodyCoordinates(b), system.getBodyCoordinates(b) + n);
        weights.resize(n);
        for (int i = 0; i < n; i++)
            weights[i] = system.getMasses()[members[i]];
        double residual;
        rotation = bestFitRotation(shape, centred, weights, residual);
        if (system.isHandednessOpen(b)) {
            for (Vector3& x : shape)
                x[2] = -x[2];
            double mirroredResidual;
            Matrix3 mirroredRotation = bestFitRotation(shape, centred, weights, mirroredResidual);
            bool mirror = (mirroredResidual < residual);
            if (mirror)
                rotation = mirroredRotation;
            system.settleHandedness(b, mirror);
        }
    }
    state.center = center;
    state.attitude = transpose(rotation);
    const Vector3* coordinates = system.getBodyCoordinates(b);
    for (int i = 0; i < n; i++)
        positions[members[i]] = toVec3(center) + toVec3(multiply(rotation, coordinates[i]));
    projectBodyVelocities(b, velocities);
}

void RigidBodyDynamics::projectBodyVelocities(int b, vector<Vec3>& velocities) {
    // The rigid motion with the linear and angular momentum of the velocities about the fitted shape.
    BodyState& state = states[b];
    const int n = system.getBodySize(b);
    const int* members = system.getBodyParticles(b);
    for (int i = 0; i < n; i++)
        system.requireFinite(velocities[members[i]], "velocity", members[i], b);
    const Vector3 velocity = system.centreOfMass(b, velocities);
    state.velocity = velocity;
    arms.resize(n);
    const Vector3 angularMomentum = particlesAngularMomentum(system, b, state.attitude, velocities, toVec3(velocity), arms.data());
    state.angularMomentum = bodyAngularMomentum(system, b, state.attitude, angularMomentum);
    Vector3 omega = multiplyTransposed(state.attitude, bodyAngularVelocity(b, multiply(state.attitude, state.angularMomentum)));
    for (int i = 0; i < n; i++)
        velocities[members[i]] = toVec3(velocity) + toVec3(cross(omega, arms[i]));
}

void RigidBodyDynamics::projectVelocities(vector<Vec3>& velocities) {
    for (size_t b = 0; b < states.size(); b++)
        projectBodyVelocities(b, velocities);
    writtenVelocities = velocities;
}

bool RigidBodyDynamics::rotatesExactly(int b, RigidBodyOptions::RotationMethod method) const {
    // A linear body's free motion is a uniform rotation about L, which both methods take exactly:
    // NO_SQUISH's turns about the perpendicular axes would move part of L onto the molecular axis,
    // where the body can carry none.
    const int kind = system.getShape(b).kind;
    return kind != RigidKindPoint && (method == RigidBodyOptions::Exact || kind == RigidKindLinear);
}

void RigidBodyDynamics::rotateNoSquish(int b, double dt) {
    BodyState& state = states[b];
    Vector3 bodyMomentum = multiply(state.attitude, state.angularMomentum);
    double attitude[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            attitude[i][j] = state.attitude[i][j];
    rigidNoSquishRotate(system.getShape(b).moments, dt, attitude, bodyMomentum.data());
    reorthonormalizeAttitudes(1, &attitude);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            state.attitude[i][j] = attitude[i][j];
}

void RigidBodyDynamics::rotateExactly(int count, const int* bodies, double dt) {
    // The exact rotation (numerics core), RigidLanes bodies side by side. Its contract holds: the
    // shapes are classified, the attitudes are kept orthonormal here and the momenta were checked
    // finite in kickAndDrift().
    RigidShape shapes[RigidLanes];
    double omega[RigidLanes][3], attitude[RigidLanes][3][3];
    for (int lane = 0; lane < count; lane++) {
        const int b = bodies[lane];
        const BodyState& state = states[b];
        shapes[lane] = system.getShape(b);
        const Vector3 w = bodyAngularVelocity(b, multiply(state.attitude, state.angularMomentum));
        for (int i = 0; i < 3; i++) {
            omega[lane][i] = w[i];
            for (int j = 0; j < 3; j++)
                attitude[lane][i][j] = state.attitude[i][j];
        }
    }
    advanceFreeRotors(count, shapes, omega, attitude, dt);
    reorthonormalizeAttitudes(count, attitude);
    for (int lane = 0; lane < count; lane++) {
        BodyState& state = states[bodies[lane]];
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                state.attitude[i][j] = attitude[lane][i][j];
    }
}

void RigidBodyDynamics::refreshMomenta(int b, const vector<Vec3>& positions, const vector<Vec3>& velocities) {
    // Rebuilding the momenta from the particles at every step would not do: the few-ulp mismatch
    // between the moments and the body coordinates would then scale L by the same factor every
    // step, a slow systematic drift. So they are rebuilt only when the velocities were changed, and
    // the changed velocities are then recorded as seen: the later stages of the step must keep the
    // momenta their kicks made, not rebuild them again from velocities that are now out of date.
    BodyState& state = states[b];
    const int n = system.getBodySize(b);
    const int* members = system.getBodyParticles(b);
    bool changed = false;
    for (int i = 0; i < n && !changed; i++)
        changed = (velocities[members[i]] != writtenVelocities[members[i]]);
    if (!changed)
        return;
    const vector<double>& masses = system.getMasses();
    const Vec3 velocity = toVec3(system.centreOfMass(b, velocities));
    Vec3 angularMomentum;
    for (int i = 0; i < n; i++) {
        int p = members[i];
        angularMomentum += (positions[p] - toVec3(state.center)).cross(velocities[p] - velocity)*masses[p];
    }
    state.velocity = toVector(velocity);
    state.angularMomentum = bodyAngularMomentum(system, b, state.attitude, toVector(angularMomentum));
    recordWrittenVelocities(b, velocities);
}

void RigidBodyDynamics::recordWrittenVelocities(int b, const vector<Vec3>& velocities) {
    const int n = system.getBodySize(b);
    const int* members = system.getBodyParticles(b);
    for (int i = 0; i < n; i++)
        writtenVelocities[members[i]] = velocities[members[i]];
}

void RigidBodyDynamics::forceAndTorque(int b, const vector<Vec3>& positions, const vector<Vec3>& forces, Vec3& force, Vec3& torque) const {
    const BodyState& state = states[b];
    const int n = system.getBodySize(b);
    const int* members = system.getBodyParticles(b);
    force = torque = Vec3();
    for (int i = 0; i < n; i++) {
        int p = members[i];
        force += forces[p];
        torque += (positions[p] - toVec3(state.center)).cross(forces[p]);
    }
}

void RigidBodyDynamics::placeParticles(int b, vector<Vec3>& positions) const {
    const BodyState& state = states[b];
    const int n = system.getBodySize(b);
    const int* members = system.getBodyParticles(b);
    const Vector3* coordinates = system.getBodyCoordinates(b);
    for (int i = 0; i < n; i++)
        positions[members[i]] = toVec3(state.center) + toVec3(multiplyTransposed(state.attitude, coordinates[i]));
}

void RigidBodyDynamics::kickAndDrift(vector<Vec3>& positions, vector<Vec3>& velocities, const vector<Vec3>& forces,
                                     double kick, double drift, RigidBodyOptions::RotationMethod method,
                                     double constraintTolerance, BodySet set) {
    requireConstraints();
    const bool kicks = (kick != 0.0), drifts = (drift != 0.0);
    const vector<int>& bodies = system.getBodySet(set);
    // The bodies go in groups of RigidLanes: each is kicked and translated, then those that rotate
    // exactly turn together (rotateExactly), then the group's particles are placed. A body whose
    // kick or displacement check fails is left out of the rest of the step.
    forEachBodyGroup(DriftLoop, bodies.size(), RigidLanes, [&](int begin, int end, FirstError& error) {
        int exact[RigidLanes], numExact = 0;
        bool moved[RigidLanes];
        for (int i = begin; i < end; i++) {
            const int b = bodies[i];
            moved[i - begin] = error.guard([&]() {
                BodyState& state = states[b];
                refreshMomenta(b, positions, velocities);
                if (kicks) {
                    Vec3 force, torque;
                    forceAndTorque(b, positions, forces, force, torque);
                    Vec3 velocity = toVec3(state.velocity) + force*(kick/system.getBodyMass(b));
                    Vec3 angularMomentum = toVec3(state.angularMomentum) + torque*kick;
                    if (!(isfinite(velocity.dot(velocity)) && isfinite(angularMomentum.dot(angularMomentum))))
                        throw OpenMMException(notFiniteMessage(system.getClassName(), b));
                    state.velocity = toVector(velocity);
                    state.angularMomentum = toVector(angularMomentum);
                }
                if (!drifts)
                    return;
                checkDisplacement("body", b, sqrt(state.velocity[0]*state.velocity[0] + state.velocity[1]*state.velocity[1] +
                                                  state.velocity[2]*state.velocity[2])*fabs(drift), drift);
                for (int k = 0; k < 3; k++)
                    state.center[k] += drift*state.velocity[k];
            }) && drifts;
            if (moved[i - begin] && rotatesExactly(b, method))
                exact[numExact++] = b;
            else if (moved[i - begin] && system.getShape(b).kind != RigidKindPoint)
                rotateNoSquish(b, drift);
        }
        rotateExactly(numExact, exact, drift);
        for (int i = begin; i < end; i++)
            if (moved[i - begin])
                placeParticles(bodies[i], positions);
    });
    if (set == SlowBodies)
        return;
    const vector<int>& free = system.getFreeParticles();
    for (int p : free) {
        if (kicks)
            velocities[p] += forces[p]*(kick*inverseMasses[p]);
        if (drifts)
            checkDisplacement("particle", p, sqrt(velocities[p].dot(velocities[p]))*fabs(drift), drift);
    }
    if (!drifts)
        return;
    if (constraints)
        previousPositions = positions;
    for (int p : free)
        positions[p] += velocities[p]*drift;
    if (constraints) {
        constraints->apply(previousPositions, positions, inverseMasses, constraintTolerance);
        // The solver reports no failure: where the constraints cannot be met from the drift (a bond
        // turned by about 90 degrees in one step, where its iteration divides by zero) it leaves
        // non-finite or far-flung positions, which the next force evaluation must not see.
        for (int p : free) {
            const Vec3 moved = positions[p] - previousPositions[p];
            checkDisplacement("particle", p, sqrt(moved.dot(moved)), drift);
            velocities[p] = moved/drift;
        }
    }
}

void RigidBodyDynamics::checkDisplacement(const char* what, int index, double distance, double drift) const {
    // Not "distance > limit": a NaN distance must stop the step too, and so must an infinite one
    // where there is no limit.
    if (distance <= geometry.displacementLimit && isfinite(distance))
        return;
    throw OpenMMException(unstableMessage(system.getClassName(), what, index, distance, drift, geometry));
}

string RigidBodyDynamics::unstableMessage(const string& className, const char* what, int index, double distance, double drift,
                                          const StepGeometry& geometry) {
    stringstream text;
    text << className << ": " << what << " " << index;
    if (isfinite(distance))
        text << " would move " << distance << " nm in one drift of " << fabs(drift) << " ps, more than " <<
                geometry.displacementLimitName << " (" << geometry.displacementLimit << " nm)";
    else
        text << " would move to a non-finite position in one drift of " << fabs(drift) << " ps";
    text << "; the simulation is unstable (try a smaller step size, or minimize the energy first)";
    return text.str();
}

string RigidBodyDynamics::notFiniteMessage(const string& className, int body) {
    return className + ": body " + to_string(body) + " has a non-finite velocity, force or torque; the simulation is unstable "
            "(try a smaller step size)";
}

void RigidBodyDynamics::getStates(vector<double>& flat) const {
    flat.resize(StateSize*states.size());
    for (size_t b = 0; b < states.size(); b++) {
        double* out = &flat[StateSize*b];
        for (int k = 0; k < 3; k++) {
            out[k] = states[b].center[k];
            out[3 + k] = states[b].velocity[k];
            out[6 + k] = states[b].angularMomentum[k];
            for (int j = 0; j < 3; j++)
                out[9 + 3*k + j] = states[b].attitude[k][j];
        }
    }
}

void RigidBodyDynamics::setStates(const vector<double>& flat) {
    for (size_t b = 0; b < states.size(); b++) {
        const double* in = &flat[StateSize*b];
        for (int k = 0; k < 3; k++) {
            states[b].center[k] = in[k];
            states[b].velocity[k] = in[3 + k];
            states[b].angularMomentum[k] = in[6 + k];
            for (int j = 0; j < 3; j++)
                states[b].attitude[k][j] = in[9 + 3*k + j];
        }
    }
}

bool RigidBodyDynamics::restoreStates(const vector<double>& flat, const vector<Vec3>& positions, const vector<Vec3>& velocities) {
    const vector<BodyState> previous = states;
    setStates(flat);
    // The states place every body particle where the positions have it, bit for bit, if they are the
    // ones that wrote these positions with these bodies' shapes.
    vector<Vec3> placed(positions);
    for (size_t b = 0; b < states.size(); b++) {
        placeParticles(b, placed);
        const int n = system.getBodySize(b);
        const int* members = system.getBodyParticles(b);
        for (int i = 0; i < n; i++)
            if (placed[members[i]] != positions[members[i]]) {
                states = previous;
                return false;
            }
    }
    writtenVelocities = velocities;
    return true;
}

double RigidBodyDynamics::thermalize(vector<Vec3>& positions, vector<Vec3>& velocities, double c, double kT,
                                     uint64_t seed, uint64_t step, double constraintTolerance) {
    requireConstraints();
    // The exact Ornstein-Uhlenbeck flow: the mean decays by c, and the variance goes from its
    // starting value s to c^2 s + (1 - c^2) m kT, so the canonical variance m kT stays fixed.
    const double noise = sqrt((1.0 - c*c)*kT);
    bodyHeat.resize(states.size());
    forEachBody(ThermalizeLoop, [&](int b) {
        BodyState& state = states[b];
        NormalStream normal(seed, b, step);
        const double mass = system.getBodyMass(b), velocityNoise = noise/sqrt(mass);
        // The heat, K' - K of the body's momenta: M (V'^2 - V^2) / 2 plus sum (L'_k^2 - L_k^2) / (2 I_k).
        double heat = -rigidTranslationalEnergy(mass, state.velocity.data());
        for (int k = 0; k < 3; k++)
            state.velocity[k] = c*state.velocity[k] + velocityNoise*normal.next();
        heat += rigidTranslationalEnergy(mass, state.velocity.data());
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
        if (system.getKind(b) != RigidKindPoint) {
            const double* moments = system.getMoments(b);
            Vector3 bodyMomentum = multiply(state.attitude, state.angularMomentum), bodyXi = multiply(state.attitude, xi);
            heat -= rigidRotationalEnergy(moments, bodyMomentum.data());
            for (int k = 0; k < 3; k++)
                bodyMomentum[k] = c*bodyMomentum[k] + noise*sqrt(moments[k])*bodyXi[k];
            heat += rigidRotationalEnergy(moments, bodyMomentum.data());
            state.angularMomentum = multiplyTransposed(state.attitude, bodyMomentum);
        }
        bodyHeat[b] = heat;
    });
    const vector<int>& free = system.getFreeParticles();
    const vector<double>& masses = system.getMasses();
    double heat = 0.0;
    for (int p : free)
        heat -= 0.5*masses[p]*velocities[p].dot(velocities[p]);
    const uint32_t firstStream = system.getNumBodies();
    for (size_t i = 0; i < free.size(); i++) {
        int p = free[i];
        NormalStream normal(seed, firstStream + i, step);
        const double velocityNoise = noise*sqrt(inverseMasses[p]);
        for (int k = 0; k < 3; k++)
            velocities[p][k] = c*velocities[p][k] + velocityNoise*normal.next();
    }
    if (constraints)
        constraints->applyToVelocities(positions, velocities, inverseMasses, constraintTolerance);
    for (int p : free)
        heat += 0.5*masses[p]*velocities[p].dot(velocities[p]);
    // Summed in body order, whatever the threads.
    for (double h : bodyHeat)
        heat += h;
    return heat;
}

void RigidBodyDynamics::scaleMomenta(vector<Vec3>& velocities, double alpha) {
    for (BodyState& state : states)
        for (int k = 0; k < 3; k++) {
            state.velocity[k] *= alpha;
            state.angularMomentum[k] *= alpha;
        }
    for (int p : system.getParticles())
        velocities[p] *= alpha;
    for (int p : system.getFreeParticles())
        velocities[p] *= alpha;
    writtenVelocities = velocities;
}

void RigidBodyDynamics::rescaleMomenta(vector<Vec3>& velocities, double targetKinetic, int dof, double c, double r1, double rest,
                                       double& kinetic, double& newKinetic) {
    double translational, rotational;
    computeKineticEnergies(velocities, translational, rotational);
    kinetic = translational + rotational;
    scaleMomenta(velocities, rigidStochasticRescaling(kinetic, targetKinetic, dof, c, r1, rest, &newKinetic));
}

void RigidBodyDynamics::closingKick(vector<Vec3>& positions, vector<Vec3>& velocities, const vector<Vec3>& forces,
                                    double kick, double constraintTolerance) {
    requireConstraints();
    writtenVelocities.resize(velocities.size());
    forEachBody(ClosingKickLoop, [&](int b) {
        BodyState& state = states[b];
        Vec3 force, torque;
        if (kick != 0.0)
            forceAndTorque(b, positions, forces, force, torque);
        // (This rounds as kickAndDrift's kick, force*(kick/mass), does not; both are kept as they were
        // when the two were the halves of the Verlet step, so that its trajectories stay bit for bit.)
        const double mass = system.getBodyMass(b);
        for (int k = 0; k < 3; k++) {
            state.velocity[k] += kick*force[k]/mass;
            state.angularMomentum[k] += kick*torque[k];
        }
        writeRigidVelocities(b, positions, velocities);
        recordWrittenVelocities(b, velocities);
    });
    if (kick != 0.0)
        for (int p : system.getFreeParticles())
            velocities[p] += forces[p]*(kick*inverseMasses[p]);
    if (constraints)
        constraints->applyToVelocities(positions, velocities, inverseMasses, constraintTolerance);
}

void RigidBodyDynamics::writeRigidVelocities(int b, const vector<Vec3>& positions, vector<Vec3>& velocities) {
    const BodyState& state = states[b];
    Vector3 omega = multiplyTransposed(state.attitude, bodyAngularVelocity(b, multiply(state.attitude, state.angularMomentum)));
    const int n = system.getBodySize(b);
    const int* members = system.getBodyParticles(b);
    for (int i = 0; i < n; i++) {
        int p = members[i];
        velocities[p] = toVec3(state.velocity) + toVec3(omega).cross(positions[p] - toVec3(state.center));
    }
}

void RigidBodyDynamics::writeBodyVelocities(const vector<Vec3>& positions, vector<Vec3>& velocities) {
    writtenVelocities.resize(velocities.size());
    forEachBody(BodyVelocitiesLoop, [&](int b) {
        writeRigidVelocities(b, positions, velocities);
        recordWrittenVelocities(b, velocities);
    });
}

void RigidBodyDynamics::computeKineticEnergies(const vector<Vec3>& velocities, double& translational, double& rotational) const {
    translational = 0.0;
    rotational = 0.0;
    const vector<double>& masses = system.getMasses();
    for (int b = 0; b < system.getNumBodies(); b++) {
        const Vec3 velocity = toVec3(system.centreOfMass(b, velocities));
        translational += 0.5*system.getBodyMass(b)*velocity.dot(velocity);
        const int n = system.getBodySize(b);
        const int* members = system.getBodyParticles(b);
        const double* scale = system.getInertiaScale(b);
        if (!rigidMomentsRaised(scale)) {
            for (int i = 0; i < n; i++) {
                Vec3 relative = velocities[members[i]] - velocity;
                rotational += 0.5*masses[members[i]]*relative.dot(relative);
            }
        }
        else {
            // Raised moments: the energy of the Hamiltonian integrated, sum L_k^2 / (2 I'_k), with L
            // the body's momentum of the particles' rigid motion about the fitted body.
            const BodyState& state = states[b];
            const Vector3 angularMomentum = particlesAngularMomentum(system, b, state.attitude, velocities, velocity, NULL);
            Vector3 bodyMomentum = multiply(state.attitude, bodyAngularMomentum(system, b, state.attitude, angularMomentum));
            rotational += rigidRotationalEnergy(system.getMoments(b), bodyMomentum.data());
        }
    }
    for (int p : system.getFreeParticles())
        translational += 0.5*masses[p]*velocities[p].dot(velocities[p]);
}

void RigidBodyDynamics::computeKickedKineticEnergies(const vector<Vec3>& positions, const vector<Vec3>& velocities,
                                                     const vector<Vec3>& forces, double kick, double constraintTolerance,
                                                     double& translational, double& rotational) {
    requireConstraints();
    translational = 0.0;
    rotational = 0.0;
    for (int b = 0; b < system.getNumBodies(); b++) {
        const BodyState& state = states[b];
        Vec3 force, torque;
        forceAndTorque(b, positions, forces, force, torque);
        const double mass = system.getBodyMass(b);
        Vector3 angularMomentum;
        Vec3 velocity;
        for (int k = 0; k < 3; k++) {
            velocity[k] = state.velocity[k] + kick*force[k]/mass;
            angularMomentum[k] = state.angularMomentum[k] + kick*torque[k];
        }
        translational += 0.5*mass*velocity.dot(velocity);
        rotational += rigidRotationalEnergy(system.getMoments(b), multiply(state.attitude, angularMomentum).data());
    }
    const vector<int>& free = system.getFreeParticles();
    if (free.empty())
        return;
    vector<Vec3> kicked = velocities;
    for (int p : free)
        kicked[p] += forces[p]*(kick*inverseMasses[p]);
    if (constraints) {
        vector<Vec3> where = positions;
        constraints->applyToVelocities(where, kicked, inverseMasses, constraintTolerance);
    }
    const vector<double>& masses = system.getMasses();
    for (int p : free)
        translational += 0.5*masses[p]*kicked[p].dot(kicked[p]);
}

double RigidBodyDynamics::computeKineticEnergy(const vector<Vec3>& velocities) const {
    if (system.hasRaisedMoments()) {
        double translational, rotational;
        computeKineticEnergies(velocities, translational, rotational);
        return translational + rotational;
    }
    const vector<double>& masses = system.getMasses();
    double energy = 0.0;
    for (size_t i = 0; i < masses.size(); i++)
        energy += 0.5*masses[i]*velocities[i].dot(velocities[i]);
    return energy;
}

} // namespace OpenMMRigid
