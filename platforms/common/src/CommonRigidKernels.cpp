#include "CommonRigidKernels.h"
#include "CommonRigidKernelSources.h"
#include "internal/RigidBodyDynamics.h"
#include "openmm/OpenMMException.h"
#include "openmm/common/ComputeForceInfo.h"
#include "openmm/common/ContextSelector.h"
#include "openmm/kernels.h"
#include <algorithm>
#include <cmath>
#include <dlfcn.h>
#include <initializer_list>
#include <map>

using namespace OpenMM;
using namespace std;

namespace OpenMMRigid {

namespace {

/** Threads of the one work group that sums the kinetic energies (rigidSumPairs). */
const int sumThreads = 128;

/** The error codes of the kernels (rigidBodies.cc). */
enum { ErrorNone = 0, ErrorBodyNotFinite = 1, ErrorBodyMoves = 2, ErrorParticleMoves = 3 };

/** The modes of rigidSumPairs (RIGID_SUM_PLAIN ... in rigidBodies.cc). */
enum { SumPlain = 0, SumRescale = 1, SumHeat = 2, SumTally = 3 };

/**
 * How many steps apart ComputeContext::reorderAtoms() reorders the atoms (OpenMM 8.6.1,
 * platforms/common/src/ComputeContext.cpp: "stepsSinceReorder < 250"). The kernel calls
 * reorderAtoms() only on the steps it would reorder (see beforeLastForces()).
 */
const int reorderInterval = 250;

/**
 * One int of host memory that a non-blocking download fills while the host goes on queueing work.
 * OpenCL copies into any host memory asynchronously. CUDA copies into pageable memory synchronously
 * (cuMemcpyDtoHAsync returns when the copy is done, which drains the stream), so there the word is
 * page-locked, from the driver's cuMemHostAlloc as OpenMM's own CUDA kernels allocate theirs. The
 * plugin links no CUDA library (the driver comes loaded with libOpenMMCUDA.so), so the two functions
 * are looked up in it; without them the word is ordinary memory: correct, but the read then waits.
 */
class HostStatusWord {
public:
    explicit HostStatusWord(bool pageLocked) {
        if (pageLocked) {
            void* driver = dlopen("libcuda.so.1", RTLD_NOW | RTLD_NOLOAD);
            if (driver != nullptr) {
                allocate = (AllocateFunction) dlsym(driver, "cuMemHostAlloc");
                release = (ReleaseFunction) dlsym(driver, "cuMemFreeHost");
                void* memory = nullptr;
                if (allocate != nullptr && release != nullptr && allocate(&memory, sizeof(int), 0) == 0)
                    pinned = (int*) memory;
                dlclose(driver);  // still loaded: libOpenMMCUDA.so needs it
            }
        }
        *get() = ErrorNone;
    }
    ~HostStatusWord() {
        if (pinned != nullptr)
            release(pinned);
    }
    HostStatusWord(const HostStatusWord&) = delete;
    HostStatusWord& operator=(const HostStatusWord&) = delete;
    int* get() {
        return pinned != nullptr ? pinned : &word;
    }
    bool isPageLocked() const {
        return pinned != nullptr;
    }
private:
    typedef int (*AllocateFunction)(void**, size_t, unsigned int);
    typedef int (*ReleaseFunction)(void*);
    AllocateFunction allocate = nullptr;
    ReleaseFunction release = nullptr;
    int* pinned = nullptr;
    int word = ErrorNone;
};

} // namespace

/**
 * Tells the platform's atom reordering what the bodies are: a body's particles are one group (so a
 * body is inside one molecule, and moves by one box vector when molecules are wrapped), and two
 * particles are interchangeable only if they hold the same place in bodies of the same size (or
 * are both outside every body), so that reordering never swaps a body atom with a free one, whose
 * constraints the free-particle solver holds by index.
 */
class CommonIntegrateRigidBodyStepKernel::BodyInfo : public ComputeForceInfo {
public:
    explicit BodyInfo(const RigidBodySystem& bodies) : bodies(bodies), role(bodies.getMasses().size(), 0),
            slot(bodies.getMasses().size(), -1) {
        for (int b = 0; b < bodies.getNumBodies(); b++)
            for (int i = 0; i < bodies.getBodySize(b); i++) {
                int p = bodies.getBodyParticles(b)[i];
                role[p] = bodies.getBodySize(b);
                slot[p] = i;
            }
    }
    bool areParticlesIdentical(int particle1, int particle2) override {
        return role[particle1] == role[particle2] && slot[particle1] == slot[particle2];
    }
    int getNumParticleGroups() override {
        return bodies.getNumBodies();
    }
    void getParticlesInGroup(int index, vector<int>& particles) override {
        particles.assign(bodies.getBodyParticles(index), bodies.getBodyParticles(index) + bodies.getBodySize(index));
    }
    bool areGroupsIdentical(int group1, int group2) override {
        return bodies.getBodySize(group1) == bodies.getBodySize(group2);
    }
private:
    const RigidBodySystem& bodies;
    vector<int> role, slot;
};

/** The state the kernel keeps: the topology and the bodies' state on the device, and the kernels. */
struct CommonIntegrateRigidBodyStepKernel::Impl {
    explicit Impl(ComputeContext& cc) : cc(cc) {
    }
    ComputeContext& cc;
    RigidBodySystem* bodies = nullptr;
    int numBodies = 0, numBodyParticles = 0, numFree = 0;
    StepGeometry geometry;
    /** The host twin of the stages, for the fits (projections after outside changes). */
    unique_ptr<RigidBodyDynamics> host;
    /** The solver of the constraints among free particles, if there are any. */
    unique_ptr<IntegrationUtilities> solver;
    /** An UpdateStateDataKernel of the platform's own, to move positions and velocities between host and device without a notice. */
    Kernel stateData;
    ComputeArray bodyStart, bodyParticles, bodyCoordinates, bodyParticleMass, bodyMass, shapes, inertiaScale, freeParticles;
    ComputeArray currentIndex, states, writtenVelocities, errorCode, errorData, energies, sums;
    /**
     * The Bussi thermostat's last step, written by rigidSumPairs on the device: [0] alpha, [1] K,
     * [2] K', [3] the work sum of K' - K since the host last took it.
     */
    ComputeArray rescaling;
    /**
     * Whether a rescaling or thermalization ran since the work was last taken, and whether the
     * device's sum holds only work already taken; the same for the tally of tallyKineticEnergy()
     * (rescaling[4], and [5] the kinetic energy its last call summed).
     */
    bool workPending = false, restartWork = false, tallyPending = false, restartTally = false;
    ComputeArray startStates, startPosq, startPosqCorrection, startVelm;
    /** The bodies of each BodySet, by index (RigidBodySystem::getBodySet()), and how many each has. */
    ComputeArray bodySets[3];
    int bodySetSize[3] = {0, 0, 0};
    /**
     * The force sets of saveForces(), by slot, each a copy of the platform's force buffer. Held by
     * pointer: a kernel keeps the address of an array argument until it runs, so an array must not
     * move when another slot is added.
     */
    vector<unique_ptr<ComputeArray> > savedForces;
    /** The Context's forces (-1) or those saveForces() kept in a slot. */
    ArrayInterface& forceSet(int forces) {
        if (forces < 0)
            return cc.getLongForceBuffer();
        if (forces >= (int) savedForces.size() || !savedForces[forces])
            throw OpenMMException("internal error: no forces were saved in slot " + to_string(forces));
        return *savedForces[forces];
    }
    ComputeKernel updateAtomOrder, recordVelocities, kickDrift, kickDriftFree, finishFreeDrift, closingKick, kickFree;
    ComputeKernel thermalizeBodies, thermalizeFree, freeKineticEnergies, scaleBodies, scaleFree, kineticEnergies, sumPairs, sumRescale;
    ComputeKernel sumAccumulate, fitTranslation;
    ComputeKernel projectBodyVelocities, kickedKineticEnergies;
    /** The velocities while computeKickedKineticEnergies() kicks the free particles' (allocated on first use). */
    ComputeArray savedVelm;
    /**
     * The failure flags of the device projections: [0] set by rigidFitTranslation for a body that did
     * not move as one translation (rigidProjectVelocities then does nothing), [1] by
     * rigidProjectVelocities for a non-finite velocity.
     */
    ComputeArray projectionFailed;
    /**
     * The step's status word (errorCode), copied without a wait before the last force evaluation and
     * waited for after it is queued (statusPending between the two): checkStatus().
     */
    unique_ptr<HostStatusWord> status;
    ComputeEvent statusRead;
    bool statusPending = false;
    /**
     * Whether the atom order was reset (a reorder not the kernel's own, a host projection, a new
     * Context), which forces the next reorderAtoms() to reorder: the next step lets it decide.
     */
    bool orderReset = true;
    /** How many times the atoms were reordered, and the count when the step began. */
    int reorders = 0, reordersAtStepStart = 0;
    /** Whether this kernel is reordering the atoms (its own call of reorderAtoms(), or a projection's setPositions()). */
    bool reordering = false;
    /** Whether positions were written by this kernel, and the step count then. */
    bool written = false;
    long long writtenStep = 0;
    ArrayInterface& posqCorrection() {
        // Read only in mixed precision; any array will do as the unused argument otherwise.
        return cc.getUseMixedPrecision() ? cc.getPosqCorrection() : cc.getPosq();
    }
    void rebuildAtomOrder() {
        updateAtomOrder->execute(cc.getNumAtoms());
    }
    void followWrapping();
    /** Whether cc.reorderAtoms() would reorder now (ComputeContext::reorderAtoms() of OpenMM 8.6.1). */
    bool reorderIsDue() const {
        return cc.getNumAtoms() > 0 && cc.getNonbondedUtilities().getUseCutoff() &&
               (cc.getStepsSinceReorder() >= reorderInterval || orderReset);
    }
    /** Throws the message of a failed stage if code says one failed (and clears the device's status). */
    void throwIfFailed(int code);
    /** The sums of the per-body energies a kernel wrote (rigidSumPairs, then a read): translation and the rest. */
    void sumEnergies(double& translational, double& rotational) {
        sumPairs->execute(sumThreads, sumThreads);
        vector<double> values;
        sums.download(values);
        translational = values[0];
        rotational = values[1];
    }
    /**
     * The device's sums (rescaling) into values, if `pending` (something was summed since they were
     * last taken): pending is cleared and restart set, so that the next sum starts again from 0 (an
     * argument of the kernel, not a write, so nothing waits for it). False, reading nothing, if not pending.
     */
    bool takeSums(bool& pending, bool& restart, vector<double>& values) {
        if (!pending)
            return false;
        rescaling.download(values);
        pending = false;
        restart = true;
        return true;
    }
    /** Waits for the status copied in beforeLastForces() (queued before the forces) and throws if a stage failed. */
    void checkStatus() {
        if (!statusPending)
            return;
        statusRead->wait();
        statusPending = false;
        throwIfFailed(*status->get());
    }
    void recordWrittenVelocities() {
        if (numBodyParticles > 0)
            recordVelocities->execute(numBodyParticles);
    }
};

namespace {

/** Marks the reorders the kernel itself asks for, for the listener, for as long as it exists. */
class OwnReorder {
public:
    explicit OwnReorder(bool& reordering) : reordering(reordering) {
        reordering = true;
    }
    ~OwnReorder() {
        reordering = false;
    }
private:
    bool& reordering;
};

} // namespace

/** Keeps the bodies coherent with the platform's arrays after the atoms were reordered. */
class CommonIntegrateRigidBodyStepKernel::ReorderListener : public ComputeContext::ReorderListener {
public:
    explicit ReorderListener(Impl* impl) : impl(impl) {
    }
    void execute() override {
        if (impl == nullptr)
            return;  // the kernel is gone; the ComputeContext owns this listener until it is destroyed
        impl->reorders++;
        impl->rebuildAtomOrder();
        // A reorder this kernel asked for moves bodies whose state is current; any other (in the
        // Context's setPositions(), a checkpoint, a Force's updateParametersInContext()) calls for a
        // fit to the positions before the next step, which the notice that comes with it, or
        // positionsAreCurrent(), brings.
        if (impl->reordering)
            impl->followWrapping();
        else {
            impl->written = false;
            impl->orderReset = true;
        }
    }
    Impl* impl;
};

void CommonIntegrateRigidBodyStepKernel::Impl::followWrapping() {
    // Reordering wraps each molecule into the box, moving posq by whole box vectors. The body's centre
    // moves by the lattice vector its first particle moved by, added exactly whatever the precision of
    // posq; a particle of the body that moved by another one (a body spread over several molecules of
    // the platform) is put back at its rigid place with its cell offset corrected, so that the
    // positions the Context reports do not change.
    if (numBodies == 0 || !cc.getNonbondedUtilities().getUsePeriodic())
        return;
    const bool mixed = cc.getUseMixedPrecision(), doublePrecision = cc.getUseDoublePrecision();
    const int numAtoms = cc.getNumAtoms();
    vector<mm_double4> positionsDouble;
    vector<mm_float4> positionsFloat, corrections;
    if (doublePrecision)
        cc.getPosq().download(positionsDouble);
    else {
        cc.getPosq().download(positionsFloat);
        if (mixed)
            cc.getPosqCorrection().download(corrections);
    }
    auto position = [&](int i, int k) -> double {
        if (doublePrecision)
            return k == 0 ? positionsDouble[i].x : k == 1 ? positionsDouble[i].y : positionsDouble[i].z;
        double x = (k == 0 ? positionsFloat[i].x : k == 1 ? positionsFloat[i].y : positionsFloat[i].z);
        if (mixed)
            x += (k == 0 ? corrections[i].x : k == 1 ? corrections[i].y : corrections[i].z);
        return x;
    };
    vector<double> flat;
    states.download(flat);
    vector<int> where(numAtoms);
    const vector<int>& order = cc.getAtomIndex();
    for (int i = 0; i < numAtoms; i++)
        where[order[i]] = i;
    Vec3 box[3];
    cc.getPeriodicBoxVectors(box[0], box[1], box[2]);
    vector<mm_int4>& offsets = cc.getPosCellOffsets();
    bool statesChanged = false, positionsChanged = false;
    for (int b = 0; b < numBodies; b++) {
        double* s = &flat[RigidBodyDynamics::StateSize*b];
        const int n = bodies->getBodySize(b);
        const int* members = bodies->getBodyParticles(b);
        const Vector3* coordinates = bodies->getBodyCoordinates(b);
        int first[3] = {0, 0, 0};
        for (int i = 0; i < n; i++) {
            const int index = where[members[i]];
            double rigid[3], d[3];
            for (int k = 0; k < 3; k++) {
                // R + A^T b_i, A row-major lab to body
                rigid[k] = s[k] + s[9 + k]*coordinates[i][0] + s[12 + k]*coordinates[i][1] + s[15 + k]*coordinates[i][2];
                d[k] = position(index, k) - rigid[k];
            }
            int cell[3];
            for (int axis = 2; axis >= 0; axis--) {
                cell[axis] = (int) round(d[axis]/box[axis][axis]);
                for (int k = 0; k <= axis; k++)
                    d[k] -= cell[axis]*box[axis][k];
            }
            if (i == 0) {
                for (int k = 0; k < 3; k++)
                    first[k] = cell[k];
            }
            else if (cell[0] != first[0] || cell[1] != first[1] || cell[2] != first[2]) {
                double x[3];
                for (int k = 0; k < 3; k++)
                    x[k] = rigid[k] + first[0]*box[0][k] + first[1]*box[1][k] + first[2]*box[2][k];
                if (doublePrecision) {
                    positionsDouble[index].x = x[0];
                    positionsDouble[index].y = x[1];
                    positionsDouble[index].z = x[2];
                }
                else {
                    positionsFloat[index].x = (float) x[0];
                    positionsFloat[index].y = (float) x[1];
                    positionsFloat[index].z = (float) x[2];
                    if (mixed) {
                        corrections[index].x = (float) (x[0] - (double) positionsFloat[index].x);
                        corrections[index].y = (float) (x[1] - (double) positionsFloat[index].y);
                        corrections[index].z = (float) (x[2] - (double) positionsFloat[index].z);
                    }
                }
                offsets[index].x += first[0] - cell[0];
                offsets[index].y += first[1] - cell[1];
                offsets[index].z += first[2] - cell[2];
                positionsChanged = true;
            }
        }
        // The centre moves after its particles were compared with the unmoved body.
        if (first[0] != 0 || first[1] != 0 || first[2] != 0) {
            for (int k = 0; k < 3; k++)
                s[k] += first[0]*box[0][k] + first[1]*box[1][k] + first[2]*box[2][k];
            statesChanged = true;
        }
    }
    if (statesChanged)
        states.upload(flat);
    if (positionsChanged) {
        if (doublePrecision)
            cc.getPosq().upload(positionsDouble);
        else {
            cc.getPosq().upload(positionsFloat);
            if (mixed)
                cc.getPosqCorrection().upload(corrections);
        }
    }
}

CommonIntegrateRigidBodyStepKernel::CommonIntegrateRigidBodyStepKernel(string name, const Platform& platform, ComputeContext& cc,
                                                                       SolverFactory makeSolver, NeighbourListRebuild rebuildNeighbourLists) :
        IntegrateRigidBodyStepKernel(name, platform), cc(cc), makeSolver(makeSolver), rebuildNeighbourLists(rebuildNeighbourLists) {
}

CommonIntegrateRigidBodyStepKernel::~CommonIntegrateRigidBodyStepKernel() {
    // The ComputeContext keeps the listener (it deletes it): it must not reach this kernel any more.
    for (auto listener : cc.getReorderListeners()) {
        ReorderListener* ours = dynamic_cast<ReorderListener*>(listener);
        if (ours != nullptr && impl && ours->impl == impl.get())
            ours->impl = nullptr;
    }
    // The device's arrays and the page-locked status word are released in the platform's context.
    ContextSelector selector(cc);
    impl.reset();
}

void CommonIntegrateRigidBodyStepKernel::initialize(ContextImpl& context, RigidBodySystem& bodies) {
    if (!cc.getSupportsDoublePrecision())
        throw OpenMMException(bodies.getClassName() + ": the " + getPlatform().getName() + " device does not support double "
                "precision, which the rigid bodies' state needs in every precision mode");
    impl.reset(new Impl(cc));
    Impl& d = *impl;
    d.bodies = &bodies;
    // Before the contexts are initialized, which finds the molecules that reordering keeps together.
    BodyInfo* info = new BodyInfo(bodies);
    cc.addForce(info);
    ContextSelector selector(cc);
    cc.initializeContexts();
    cc.invalidateMolecules(info, true, false);  // if another integrator initialized the contexts first
    d.numBodies = bodies.getNumBodies();
    d.numBodyParticles = bodies.getParticles().size();
    d.numFree = bodies.getFreeParticles().size();
    const int numAtoms = cc.getNumAtoms();

    vector<int> start(d.numBodies + 1);
    for (int b = 0; b <= d.numBodies; b++)
        start[b] = bodies.getBodyStart(b);
    vector<double> particleMass(max(1, d.numBodyParticles), 0.0), mass(max(1, d.numBodies), 0.0);
    for (int i = 0; i < d.numBodyParticles; i++)
        particleMass[i] = bodies.getMasses()[bodies.getParticles()[i]];
    for (int b = 0; b < d.numBodies; b++)
        mass[b] = bodies.getBodyMass(b);
    vector<int> particles = bodies.getParticles(), free = bodies.getFreeParticles();
    particles.resize(max(1, d.numBodyParticles), 0);
    free.resize(max(1, d.numFree), 0);
    d.bodyStart.initialize<int>(cc, start.size(), "rigidBodyStart");
    d.bodyStart.upload(start);
    d.bodyParticles.initialize<int>(cc, particles.size(), "rigidBodyParticles");
    d.bodyParticles.upload(particles);
    d.bodyParticleMass.initialize<double>(cc, particleMass.size(), "rigidBodyParticleMass");
    d.bodyParticleMass.upload(particleMass);
    d.bodyMass.initialize<double>(cc, mass.size(), "rigidBodyMass");
    d.bodyMass.upload(mass);
    d.freeParticles.initialize<int>(cc, free.size(), "rigidFreeParticles");
    d.freeParticles.upload(free);
    // Body coordinates and shapes: explicit bodies get theirs from the first positions, later; both are
    // uploaded at each projection (uploadShapes()).
    d.bodyCoordinates.initialize<double>(cc, 3*particles.size(), "rigidBodyCoordinates");
    d.shapes.initialize(cc, max(1, d.numBodies), sizeof(RigidShape), "rigidBodyShapes");
    d.inertiaScale.initialize<double>(cc, 3*max(1, d.numBodies), "rigidInertiaScale");
    d.states.initialize<double>(cc, RigidBodyDynamics::StateSize*max(1, d.numBodies), "rigidBodyStates");
    d.startStates.initialize<double>(cc, d.states.getSize(), "rigidBodyStartStates");
    d.writtenVelocities.initialize<double>(cc, 3*particles.size(), "rigidWrittenVelocities");
    d.currentIndex.initialize<int>(cc, numAtoms, "rigidCurrentIndex");
    d.errorCode.initialize<int>(cc, 1, "rigidErrorCode");
    d.errorCode.upload(vector<int>(1, ErrorNone));
    d.errorData.initialize<double>(cc, 3, "rigidErrorData");
    d.status.reset(new HostStatusWord(getPlatform().getName() == "CUDA"));
    d.statusRead = cc.createEvent();
    d.energies.initialize<double>(cc, 2*max(1, d.numBodies + d.numFree), "rigidKineticEnergies");
    d.sums.initialize<double>(cc, 2, "rigidKineticEnergySums");
    d.rescaling.initialize<double>(cc, 6, "rigidRescaling");
    d.rescaling.upload(vector<double>{1.0, 0.0, 0.0, 0.0, 0.0, 0.0});
    d.startPosq.initialize(cc, cc.getPosq().getSize(), cc.getPosq().getElementSize(), "rigidStartPosq");
    if (cc.getUseMixedPrecision())
        d.startPosqCorrection.initialize(cc, cc.getPosqCorrection().getSize(), cc.getPosqCorrection().getElementSize(),
                                         "rigidStartPosqCorrection");
    d.startVelm.initialize(cc, cc.getVelm().getSize(), cc.getVelm().getElementSize(), "rigidStartVelm");

    map<string, string> defines;
    defines["RIGID_SUM_THREADS"] = cc.intToString(sumThreads);
    ComputeProgram program = cc.compileProgram(CommonRigidKernelSources::core + CommonRigidKernelSources::rigidBodies, defines);
    ArrayInterface& posq = cc.getPosq();
    ArrayInterface& correction = d.posqCorrection();
    ArrayInterface& velm = cc.getVelm();
    ArrayInterface& force = cc.getLongForceBuffer();
    const int padded = cc.getPaddedNumAtoms();

    d.updateAtomOrder = program->createKernel("rigidUpdateAtomOrder");
    d.updateAtomOrder->addArg(numAtoms);
    d.updateAtomOrder->addArg(cc.getAtomIndexArray());
    d.updateAtomOrder->addArg(d.currentIndex);

    d.recordVelocities = program->createKernel("rigidRecordVelocities");
    d.recordVelocities->addArg(d.numBodyParticles);
    d.recordVelocities->addArg(d.bodyParticles);
    d.recordVelocities->addArg(d.currentIndex);
    d.recordVelocities->addArg(velm);
    d.recordVelocities->addArg(d.writtenVelocities);

    d.kickDrift = program->createKernel("rigidKickDrift");
    d.kickDrift->addArg(d.numBodies);
    for (ArrayInterface* array : initializer_list<ArrayInterface*>{&d.bodyStart, &d.bodyParticles, &d.bodyCoordinates, &d.bodyParticleMass, &d.bodyMass, &d.shapes,
                                  &d.currentIndex, &d.states, &d.writtenVelocities, &posq, &correction, &velm, &force})
        d.kickDrift->addArg(*array);
    d.kickDrift->addArg(padded);
    for (int i = 0; i < 4; i++)
        d.kickDrift->addArg();  // kick, drift, noSquish, displacementLimit (arguments 15 to 18)
    d.kickDrift->addArg(d.errorCode);
    d.kickDrift->addArg(d.errorData);
    d.kickDrift->addArg(d.inertiaScale);
    for (int set = 0; set < 3; set++) {
        vector<int> list = bodies.getBodySet((BodySet) set);
        d.bodySetSize[set] = list.size();
        list.resize(max<size_t>(1, list.size()), 0);
        d.bodySets[set].initialize<int>(cc, list.size(), "rigidBodySet");
        d.bodySets[set].upload(list);
    }
    d.kickDrift->addArg(d.bodySets[AllBodies]);  // bodyList (22)

    d.solver.reset(bodies.getFreeConstraintSystem() != nullptr ? makeSolver(*bodies.getFreeConstraintSystem()) : nullptr);
    d.kickDriftFree = program->createKernel("rigidKickDriftFree");
    d.kickDriftFree->addArg(d.numFree);
    for (ArrayInterface* array : initializer_list<ArrayInterface*>{&d.freeParticles, &d.currentIndex, &posq, &correction, &velm, &force})
        d.kickDriftFree->addArg(*array);
    d.kickDriftFree->addArg(padded);
    for (int i = 0; i < 3; i++)
        d.kickDriftFree->addArg();  // kick, drift, displacementLimit (args 8 to 10)
    d.kickDriftFree->addArg((int) (d.solver != nullptr));
    if (d.solver)
        d.kickDriftFree->addArg(d.solver->getPosDelta());
    else
        d.kickDriftFree->addArg(velm);  // not read without constraints
    d.kickDriftFree->addArg(d.errorCode);
    d.kickDriftFree->addArg(d.errorData);

    if (d.solver) {
        d.finishFreeDrift = program->createKernel("rigidFinishFreeDrift");
        d.finishFreeDrift->addArg(d.numFree);
        for (ArrayInterface* array : initializer_list<ArrayInterface*>{&d.freeParticles, &d.currentIndex, &posq, &correction, &velm, &d.solver->getPosDelta()})
            d.finishFreeDrift->addArg(*array);
        d.finishFreeDrift->addArg();  // drift (7)
        d.finishFreeDrift->addArg();  // displacementLimit (8)
        d.finishFreeDrift->addArg(d.errorCode);
        d.finishFreeDrift->addArg(d.errorData);
    }

    d.closingKick = program->createKernel("rigidClosingKick");
    d.closingKick->addArg(d.numBodies);
    for (ArrayInterface* array : initializer_list<ArrayInterface*>{&d.bodyStart, &d.bodyParticles, &d.bodyCoordinates, &d.bodyMass, &d.shapes, &d.currentIndex,
                                  &d.states, &d.writtenVelocities, &velm, &force})
        d.closingKick->addArg(*array);
    d.closingKick->addArg(padded);
    d.closingKick->addArg();  // kick (12)

    d.kickFree = program->createKernel("rigidKickFree");
    d.kickFree->addArg(d.numFree);
    for (ArrayInterface* array : initializer_list<ArrayInterface*>{&d.freeParticles, &d.currentIndex, &velm, &force})
        d.kickFree->addArg(*array);
    d.kickFree->addArg(padded);
    d.kickFree->addArg();  // kick (6)

    d.thermalizeBodies = program->createKernel("rigidThermalize");
    d.thermalizeBodies->addArg(d.numBodies);
    d.thermalizeBodies->addArg(d.bodyMass);
    d.thermalizeBodies->addArg(d.shapes);
    d.thermalizeBodies->addArg(d.states);
    for (int i = 0; i < 4; i++)
        d.thermalizeBodies->addArg();  // c, noise, seed, counter (4 to 7)
    d.thermalizeBodies->addArg(d.energies);

    d.thermalizeFree = program->createKernel("rigidThermalizeFree");
    d.thermalizeFree->addArg(d.numFree);
    d.thermalizeFree->addArg(d.numBodies);
    d.thermalizeFree->addArg(d.freeParticles);
    d.thermalizeFree->addArg(d.currentIndex);
    d.thermalizeFree->addArg(velm);
    for (int i = 0; i < 4; i++)
        d.thermalizeFree->addArg();  // c, noise, seed, counter (5 to 8)
    d.thermalizeFree->addArg(d.energies);

    d.freeKineticEnergies = program->createKernel("rigidFreeKineticEnergies");
    d.freeKineticEnergies->addArg(d.numFree);
    d.freeKineticEnergies->addArg(d.numBodies);
    for (ArrayInterface* array : initializer_list<ArrayInterface*>{&d.freeParticles, &d.currentIndex, &velm, &d.energies})
        d.freeKineticEnergies->addArg(*array);

    d.scaleBodies = program->createKernel("rigidScaleMomenta");
    d.scaleBodies->addArg(d.numBodies);
    for (ArrayInterface* array : initializer_list<ArrayInterface*>{&d.bodyStart, &d.bodyParticles, &d.currentIndex, &d.states, &d.writtenVelocities, &velm})
        d.scaleBodies->addArg(*array);
    d.scaleBodies->addArg(d.rescaling);

    d.scaleFree = program->createKernel("rigidScaleFree");
    d.scaleFree->addArg(d.numFree);
    d.scaleFree->addArg(d.freeParticles);
    d.scaleFree->addArg(d.currentIndex);
    d.scaleFree->addArg(velm);
    d.scaleFree->addArg(d.rescaling);

    d.kineticEnergies = program->createKernel("rigidKineticEnergies");
    d.kineticEnergies->addArg(d.numBodies);
    d.kineticEnergies->addArg(d.numFree);
    for (ArrayInterface* array : initializer_list<ArrayInterface*>{&d.bodyStart, &d.bodyParticles, &d.bodyParticleMass, &d.bodyMass, &d.freeParticles, &d.currentIndex,
                                  &velm, &d.energies, &d.bodyCoordinates, &d.shapes, &d.inertiaScale, &d.states})
        d.kineticEnergies->addArg(*array);

    d.kickedKineticEnergies = program->createKernel("rigidKickedKineticEnergies");
    d.kickedKineticEnergies->addArg(d.numBodies);
    d.kickedKineticEnergies->addArg(d.numFree);
    for (ArrayInterface* array : initializer_list<ArrayInterface*>{&d.bodyStart, &d.bodyParticles, &d.bodyCoordinates, &d.bodyMass,
                                  &d.shapes, &d.freeParticles, &d.currentIndex, &d.states, &velm, &force})
        d.kickedKineticEnergies->addArg(*array);
    d.kickedKineticEnergies->addArg(padded);
    d.kickedKineticEnergies->addArg(d.energies);
    d.kickedKineticEnergies->addArg();  // kick (14)

    // The same kernel three times: the plain sums, the sums with the thermostat's step after them, and
    // the sums added to the heat or the tally (its mode set at each call).
    d.sumPairs = program->createKernel("rigidSumPairs");
    d.sumRescale = program->createKernel("rigidSumPairs");
    d.sumAccumulate = program->createKernel("rigidSumPairs");
    for (ComputeKernel* kernel : {&d.sumPairs, &d.sumRescale, &d.sumAccumulate}) {
        (*kernel)->addArg(d.numBodies + d.numFree);
        (*kernel)->addArg(d.energies);
        (*kernel)->addArg(d.sums);
        (*kernel)->addArg(kernel == &d.sumRescale ? SumRescale : SumPlain);  // mode (3)
        (*kernel)->addArg(0.0);                              // targetKinetic (4)
        (*kernel)->addArg(0);                                // dof (5)
        (*kernel)->addArg(1.0);                              // c (6)
        (*kernel)->addArg(0.0);                              // r1 (7)
        (*kernel)->addArg(0.0);                              // rest (8)
        (*kernel)->addArg(0);                                // restart (9)
        (*kernel)->addArg(d.rescaling);
        (*kernel)->addArg(1.0);                              // sign (11)
    }

    d.projectionFailed.initialize<int>(cc, 2, "rigidProjectionFailed");
    d.fitTranslation = program->createKernel("rigidFitTranslation");
    d.fitTranslation->addArg(d.numBodies);
    for (ArrayInterface* array : initializer_list<ArrayInterface*>{&d.bodyStart, &d.bodyParticles, &d.bodyCoordinates,
                                  &d.bodyParticleMass, &d.bodyMass, &d.currentIndex, &d.states, &posq, &correction})
        d.fitTranslation->addArg(*array);
    // What a translation may leave of a rigid shape: rounding to the precision of the positions.
    d.fitTranslation->addArg(cc.getUseDoublePrecision() ? 1e-9 : 1e-5);
    d.fitTranslation->addArg(d.projectionFailed);

    d.projectBodyVelocities = program->createKernel("rigidProjectVelocities");
    d.projectBodyVelocities->addArg(d.numBodies);
    for (ArrayInterface* array : initializer_list<ArrayInterface*>{&d.bodyStart, &d.bodyParticles, &d.bodyCoordinates,
                                  &d.bodyParticleMass, &d.bodyMass, &d.shapes, &d.currentIndex, &d.states, &d.writtenVelocities,
                                  &velm, &d.projectionFailed, &d.inertiaScale})
        d.projectBodyVelocities->addArg(*array);

    d.rebuildAtomOrder();
    cc.addReorderListener(new ReorderListener(impl.get()));
    d.host.reset(new RigidBodyDynamics(bodies, nullptr, nullptr));
    d.stateData = getPlatform().createKernel(UpdateStateDataKernel::Name(), context);
    d.stateData.getAs<UpdateStateDataKernel>().initialize(context.getSystem());
}

void CommonIntegrateRigidBodyStepKernel::setGeometry(ContextImpl& context, const StepGeometry& geometry) {
    impl->geometry = geometry;
    impl->host->setGeometry(geometry);
}

void CommonIntegrateRigidBodyStepKernel::beginStep(ContextImpl& context, const StepGeometry& geometry) {
    setGeometry(context, geometry);
    Impl& d = *impl;
    ContextSelector selector(cc);
    cc.getPosq().copyTo(d.startPosq);
    if (cc.getUseMixedPrecision())
        cc.getPosqCorrection().copyTo(d.startPosqCorrection);
    cc.getVelm().copyTo(d.startVelm);
    d.states.copyTo(d.startStates);
    d.reordersAtStepStart = d.reorders;
}

void CommonIntegrateRigidBodyStepKernel::abandonStep(ContextImpl& context) {
    Impl& d = *impl;
    ContextSelector selector(cc);
    if (d.statusPending) {
        // The step stopped before its status was checked (a Force threw): the copy must be done
        // before the word is used again.
        d.statusRead->wait();
        d.statusPending = false;
    }
    d.errorCode.upload(vector<int>(1, ErrorNone));
    // The copies are in the atom order of the step's start: the atoms are reordered only right before
    // the step's last force evaluation, after every stage that can fail has been checked.
    if (d.reorders == d.reordersAtStepStart) {
        d.startPosq.copyTo(cc.getPosq());
        if (cc.getUseMixedPrecision())
            d.startPosqCorrection.copyTo(cc.getPosqCorrection());
        d.startVelm.copyTo(cc.getVelm());
        d.startStates.copyTo(d.states);
        context.computeVirtualSites();
    }
    d.written = false;
}

void CommonIntegrateRigidBodyStepKernel::project(ContextImpl& context) {
    Impl& d = *impl;
    ContextSelector selector(cc);
    // Positions that moved each body by one translation since the kernel wrote them (a barostat's
    // move, every few steps): the fit is done on the device, the velocities are projected there if
    // it succeeded, and the host reads both flags at once. Anything else is fitted on the host.
    if (d.written && d.numBodies > 0) {
        cc.clearBuffer(d.projectionFailed);
        d.fitTranslation->execute(d.numBodies);
        d.projectBodyVelocities->execute(d.numBodies);
        int failed[2];
        d.projectionFailed.download(failed);
        if (!failed[0] && !failed[1]) {
            context.computeVirtualSites();
            d.writtenStep = cc.getStepCount();
            return;
        }
    }
    // The fit on the host (RigidBodyDynamics::project, as on the Reference platform): outside changes
    // (new positions, a barostat's move, a checkpoint) are rare next to steps.
    vector<Vec3> positions, velocities;
    context.getPositions(positions);
    context.getVelocities(velocities);
    d.host->project(positions, velocities);
    // The shapes of explicit bodies are known from the first projection on, and then never change.
    vector<double> coordinates(d.bodyCoordinates.getSize(), 0.0);
    for (int i = 0; i < d.numBodyParticles; i++)
        for (int k = 0; k < 3; k++)
            coordinates[3*i + k] = d.bodies->getBodyCoordinates()[i][k];
    d.bodyCoordinates.upload(coordinates);
    vector<RigidShape> shapes(d.shapes.getSize());
    vector<double> scale(d.inertiaScale.getSize(), 1.0);
    for (int b = 0; b < d.numBodies; b++) {
        shapes[b] = d.bodies->getShape(b);
        for (int k = 0; k < 3; k++)
            scale[3*b + k] = d.bodies->getInertiaScale(b)[k];
    }
    d.shapes.upload(shapes);
    d.inertiaScale.upload(scale);
    vector<double> flat;
    d.host->getStates(flat);
    flat.resize(d.states.getSize(), 0.0);
    d.states.upload(flat);
    // The listener keeps currentIndex through reorders, but not every change of the order reaches it
    // (without these two rebuilds test_explicit_body_shape_from_first_positions fails on OpenCL; the
    // path that bypasses the listener is not identified): rebuilt before and after the upload.
    d.rebuildAtomOrder();
    UpdateStateDataKernel& stateData = d.stateData.getAs<UpdateStateDataKernel>();
    {
        OwnReorder own(d.reordering);
        stateData.setPositions(context, positions);
    }
    stateData.setVelocities(context, velocities);
    d.rebuildAtomOrder();
    d.recordWrittenVelocities();
    context.computeVirtualSites();
    d.orderReset = true;
    d.written = true;
    d.writtenStep = cc.getStepCount();
}

bool CommonIntegrateRigidBodyStepKernel::projectVelocitiesOnDevice(ContextImpl& context) {
    Impl& d = *impl;
    if (d.numBodies == 0)
        return true;
    cc.clearBuffer(d.projectionFailed);
    d.projectBodyVelocities->execute(d.numBodies);
    int failed[2];
    d.projectionFailed.download(failed);
    return !failed[1];
}

void CommonIntegrateRigidBodyStepKernel::projectVelocities(ContextImpl& context) {
    Impl& d = *impl;
    ContextSelector selector(cc);
    if (projectVelocitiesOnDevice(context))
        return;
    // A non-finite velocity: the host's projection says which particle has it.
    vector<double> flat;
    d.states.download(flat);
    flat.resize(RigidBodyDynamics::StateSize*d.numBodies);
    d.host->setStates(flat);
    vector<Vec3> velocities;
    context.getVelocities(velocities);
    d.host->projectVelocities(velocities);
}

bool CommonIntegrateRigidBodyStepKernel::positionsAreCurrent(ContextImpl& context) const {
    // Whatever changes the positions through the Context sends a notice; what steps without one (the
    // other integrator of a CompoundIntegrator) advances the step count. A comparison of the
    // positions themselves would cost a copy from the device at every step.
    return impl->written && impl->writtenStep == cc.getStepCount();
}

void CommonIntegrateRigidBodyStepKernel::saveForces(ContextImpl& context, int slot) {
    Impl& d = *impl;
    ContextSelector selector(cc);
    if (slot >= (int) d.savedForces.size())
        d.savedForces.resize(slot + 1);
    ArrayInterface& force = cc.getLongForceBuffer();
    if (!d.savedForces[slot]) {
        d.savedForces[slot].reset(new ComputeArray());
        d.savedForces[slot]->initialize(cc, force.getSize(), force.getElementSize(), "rigidSavedForces");
    }
    force.copyTo(*d.savedForces[slot]);
}

void CommonIntegrateRigidBodyStepKernel::kickAndDrift(ContextImpl& context, double kick, double drift,
                                                      RigidBodyOptions::RotationMethod method, double constraintTolerance,
                                                      int forces, BodySet set) {
    Impl& d = *impl;
    ContextSelector selector(cc);
    const double limit = d.geometry.displacementLimit;
    ArrayInterface& force = d.forceSet(forces);
    if (d.bodySetSize[set] > 0) {
        d.kickDrift->setArg(0, d.bodySetSize[set]);
        d.kickDrift->setArg(13, force);
        d.kickDrift->setArg(15, kick);
        d.kickDrift->setArg(16, drift);
        d.kickDrift->setArg(17, (int) (method == RigidBodyOptions::NoSquish));
        d.kickDrift->setArg(18, limit);
        d.kickDrift->setArg(22, d.bodySets[set]);
        d.kickDrift->execute(d.bodySetSize[set]);
    }
    if (d.numFree > 0 && set != SlowBodies && drift != 0.0) {
        d.kickDriftFree->setArg(6, force);
        d.kickDriftFree->setArg(8, kick);
        d.kickDriftFree->setArg(9, drift);
        d.kickDriftFree->setArg(10, limit);
        d.kickDriftFree->execute(d.numFree);
        if (d.solver) {
            d.solver->applyConstraints(constraintTolerance);
            d.finishFreeDrift->setArg(7, drift);
            d.finishFreeDrift->setArg(8, limit);
            d.finishFreeDrift->execute(d.numFree);
        }
    }
    else if (d.numFree > 0 && set != SlowBodies && kick != 0.0) {
        // A kick alone: no drift, no constraint.
        d.kickFree->setArg(4, force);
        d.kickFree->setArg(6, kick);
        d.kickFree->execute(d.numFree);
    }
}

void CommonIntegrateRigidBodyStepKernel::closingKick(ContextImpl& context, double kick, double constraintTolerance, int forces) {
    Impl& d = *impl;
    ContextSelector selector(cc);
    ArrayInterface& force = d.forceSet(forces);
    if (d.numBodies > 0) {
        d.closingKick->setArg(10, force);
        d.closingKick->setArg(12, kick);
        d.closingKick->execute(d.numBodies);
    }
    if (d.numFree > 0 && kick != 0.0) {
        d.kickFree->setArg(4, force);
        d.kickFree->setArg(6, kick);
        d.kickFree->execute(d.numFree);
    }
    if (d.solver)
        d.solver->applyVelocityConstraints(constraintTolerance);
    // After the last force evaluation and this stage are queued: the host waits here while the device works.
    d.checkStatus();
}

void CommonIntegrateRigidBodyStepKernel::thermalize(ContextImpl& context, double c, double kT, uint64_t seed, uint64_t counter,
                                                    double constraintTolerance, bool heat) {
    Impl& d = *impl;
    ContextSelector selector(cc);
    if (d.numBodies + d.numFree == 0)
        return;
    const double noise = sqrt((1.0 - c*c)*kT);
    if (d.numBodies > 0) {
        d.thermalizeBodies->setArg(4, c);
        d.thermalizeBodies->setArg(5, noise);
        d.thermalizeBodies->setArg(6, seed);
        d.thermalizeBodies->setArg(7, counter);
        d.thermalizeBodies->execute(d.numBodies);
    }
    if (d.numFree > 0) {
        d.thermalizeFree->setArg(5, c);
        d.thermalizeFree->setArg(6, noise);
        d.thermalizeFree->setArg(7, seed);
        d.thermalizeFree->setArg(8, counter);
        d.thermalizeFree->execute(d.numFree);
    }
    if (d.solver)
        d.solver->applyVelocityConstraints(constraintTolerance);
    if (!heat)
        return;
    if (d.solver)
        d.freeKineticEnergies->execute(d.numFree);
    // The heat each thread wrote, summed into the thermostat's work on the device.
    d.sumAccumulate->setArg(3, (int) SumHeat);
    d.sumAccumulate->setArg(9, d.restartWork ? 1 : 0);
    d.sumAccumulate->execute(sumThreads, sumThreads);
    d.restartWork = false;
    d.workPending = true;
}

void CommonIntegrateRigidBodyStepKernel::rescaleMomenta(ContextImpl& context, double targetKinetic, int dof, double c, double r1,
                                                        double rest) {
    Impl& d = *impl;
    ContextSelector selector(cc);
    if (d.numBodies + d.numFree == 0)
        return;
    // The kinetic energies, their sum and the factor (rigidSumPairs' thread 0), the scaling: all on
    // the device, the factor read there by the scaling kernels.
    d.kineticEnergies->execute(d.numBodies + d.numFree);
    d.sumRescale->setArg(4, targetKinetic);
    d.sumRescale->setArg(5, dof);
    d.sumRescale->setArg(6, c);
    d.sumRescale->setArg(7, r1);
    d.sumRescale->setArg(8, rest);
    d.sumRescale->setArg(9, d.restartWork ? 1 : 0);
    d.sumRescale->execute(sumThreads, sumThreads);
    d.restartWork = false;
    d.workPending = true;
    if (d.numBodies > 0)
        d.scaleBodies->execute(d.numBodies);
    if (d.numFree > 0)
        d.scaleFree->execute(d.numFree);
}

void CommonIntegrateRigidBodyStepKernel::getRescalingEnergies(ContextImpl& context, double& kinetic, double& newKinetic) {
    Impl& d = *impl;
    ContextSelector selector(cc);
    vector<double> values;
    d.rescaling.download(values);
    kinetic = values[1];
    newKinetic = values[2];
}

void CommonIntegrateRigidBodyStepKernel::tallyKineticEnergy(ContextImpl& context, double sign) {
    Impl& d = *impl;
    ContextSelector selector(cc);
    if (d.numBodies + d.numFree == 0)
        return;
    d.kineticEnergies->execute(d.numBodies + d.numFree);
    d.sumAccumulate->setArg(3, (int) SumTally);
    d.sumAccumulate->setArg(9, d.restartTally ? 1 : 0);
    d.sumAccumulate->setArg(11, sign);
    d.sumAccumulate->execute(sumThreads, sumThreads);
    d.restartTally = false;
    d.tallyPending = true;
}

double CommonIntegrateRigidBodyStepKernel::takeTally(ContextImpl& context, double& kinetic) {
    ContextSelector selector(cc);
    vector<double> values;
    if (!impl->takeSums(impl->tallyPending, impl->restartTally, values)) {
        kinetic = 0.0;
        return 0.0;
    }
    kinetic = values[5];
    return values[4];
}

double CommonIntegrateRigidBodyStepKernel::takeThermostatWork(ContextImpl& context) {
    ContextSelector selector(cc);
    vector<double> values;
    return impl->takeSums(impl->workPending, impl->restartWork, values) ? values[3] : 0.0;
}

void CommonIntegrateRigidBodyStepKernel::computeKineticEnergies(ContextImpl& context, double& translational, double& rotational) {
    Impl& d = *impl;
    ContextSelector selector(cc);
    translational = rotational = 0.0;
    if (d.numBodies + d.numFree == 0)
        return;
    d.kineticEnergies->execute(d.numBodies + d.numFree);
    d.sumEnergies(translational, rotational);
}

void CommonIntegrateRigidBodyStepKernel::computeKickedKineticEnergies(ContextImpl& context, double kick, double constraintTolerance,
                                                                      int forces, double& translational, double& rotational) {
    Impl& d = *impl;
    ContextSelector selector(cc);
    ArrayInterface& force = d.forceSet(forces);
    translational = rotational = 0.0;
    if (d.numBodies + d.numFree == 0)
        return;
    if (d.numFree > 0) {
        // The free particles' velocities kicked and projected in place, and put back afterwards.
        if (!d.savedVelm.isInitialized())
            d.savedVelm.initialize(cc, cc.getVelm().getSize(), cc.getVelm().getElementSize(), "rigidSavedVelm");
        cc.getVelm().copyTo(d.savedVelm);
        d.kickFree->setArg(4, force);
        d.kickFree->setArg(6, kick);
        d.kickFree->execute(d.numFree);
        if (d.solver)
            d.solver->applyVelocityConstraints(constraintTolerance);
    }
    d.kickedKineticEnergies->setArg(11, force);
    d.kickedKineticEnergies->setArg(14, kick);
    d.kickedKineticEnergies->execute(d.numBodies + d.numFree);
    d.sumEnergies(translational, rotational);
    if (d.numFree > 0)
        d.savedVelm.copyTo(cc.getVelm());
}

double CommonIntegrateRigidBodyStepKernel::computeKineticEnergy(ContextImpl& context) {
    ContextSelector selector(cc);
    if (impl->bodies->hasRaisedMoments()) {
        // The energy of the Hamiltonian integrated: that of the raised moments, not sum m v^2 / 2.
        double translational, rotational;
        computeKineticEnergies(context, translational, rotational);
        return translational + rotational;
    }
    return cc.getIntegrationUtilities().computeKineticEnergy(0.0);
}

void CommonIntegrateRigidBodyStepKernel::Impl::throwIfFailed(int code) {
    if (code == ErrorNone)
        return;
    vector<double> data;
    errorData.download(data);
    errorCode.upload(vector<int>(1, ErrorNone));
    const string& className = bodies->getClassName();
    if (code == ErrorBodyNotFinite)
        throw OpenMMException(RigidBodyDynamics::notFiniteMessage(className, (int) data[0]));
    throw OpenMMException(RigidBodyDynamics::unstableMessage(className, code == ErrorBodyMoves ? "body" : "particle", (int) data[0],
                                                             data[1], data[2], geometry));
}

void CommonIntegrateRigidBodyStepKernel::beforeLastForces(ContextImpl& context) {
    Impl& d = *impl;
    ContextSelector selector(cc);
    if (d.reorderIsDue()) {
        // A step that reorders (one in 250): the reorder downloads the atoms anyway, and must not
        // happen on a failed step (abandonStep() restores copies in the step's atom order), so the
        // status is read first, with a wait. Reordering right before the force evaluation keeps the
        // forces about to be computed valid for the next step's first kick.
        int code;
        d.errorCode.download(&code);
        d.throwIfFailed(code);
        OwnReorder own(d.reordering);
        d.orderReset = false;
        cc.reorderAtoms();
        return;
    }
    // Any other step: the status is copied without a wait and checked once the force evaluation is
    // queued (checkStatus(), in closingKick()), so that the device never idles while the host
    // launches the force kernels. reorderAtoms() is not called: it would not reorder (unless a
    // NonbondedUtilities asked for an early reorder, which then waits for the next due step), and
    // this is what it does when it does not.
    d.errorCode.download(d.status->get(), false);
    d.statusRead->enqueue();
    d.statusPending = true;
    cc.setStepsSinceReorder(cc.getStepsSinceReorder() + 1);
    cc.setAtomsWereReordered(false);
}

void CommonIntegrateRigidBodyStepKernel::boxChanged(ContextImpl& context) {
    // The platform rebuilds a neighbour list only when a particle has moved by half the padding since
    // the last build: a box made smaller without moving the particles would keep the old box's list,
    // which misses the pairs that the new box's images bring within the cutoff.
    ContextSelector selector(cc);
    if (cc.getNonbondedUtilities().getUseCutoff())
        rebuildNeighbourLists();
}

void CommonIntegrateRigidBodyStepKernel::finishStep(ContextImpl& context, double dt) {
    Impl& d = *impl;
    for (auto ctx : cc.getAllContexts()) {
        ctx->setTime(ctx->getTime() + dt);
        ctx->setStepCount(ctx->getStepCount() + 1);
    }
    d.written = true;
    d.writtenStep = cc.getStepCount();
}

} // namespace OpenMMRigid
