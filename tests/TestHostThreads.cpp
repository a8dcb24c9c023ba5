/* -------------------------------------------------------------------------- *
 *                               OpenMM-Rigid                                 *
 * -------------------------------------------------------------------------- *
 * The host stages' use of threads. ThreadedLoopChoice, which decides per     *
 * loop whether the threads pay, is driven with made-up timings: it must      *
 * settle on the faster way, keep probing the other rarely, follow a change   *
 * of load and not be misled for long by one slow run. RigidBodyDynamics on   *
 * a pool of four "threads" that run one after the other in the caller must   *
 * give bit for bit the results of the serial stages (the ranges and the      *
 * groups of RigidLanes bodies cut at odd places), and its array comparison   *
 * must find a difference in any thread's range.                              *
 * -------------------------------------------------------------------------- */

#include "internal/RigidBodyDynamics.h"
#include "internal/RigidBodySystem.h"
#include "openmm/OpenMMException.h"
#include "openmm/System.h"
#include "openmm/Vec3.h"
#include <cmath>
#include <cstring>
#include <iostream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

using namespace OpenMM;
using namespace OpenMMRigid;
using namespace std;

namespace {

void check(bool condition, const string& what) {
    if (!condition)
        throw OpenMMException("TestHostThreads: " + what);
}

template <class T>
string describe(const string& text, T value) {
    stringstream out;
    out << text << value;
    return out.str();
}

/**
 * Run a loop `runs` times whose runs take `serial` seconds serially and `threaded` seconds on the
 * threads, as the choice says; the first run of the loop gets `firstSerial` seconds if it is serial.
 * Returns the sequence of choices (true: threads).
 */
vector<bool> drive(ThreadedLoopChoice& choice, int runs, double serial, double threaded, double firstSerial = -1.0) {
    vector<bool> used;
    for (int i = 0; i < runs; i++) {
        const bool threads = choice.useThreads();
        double seconds = (threads ? threaded : serial);
        if (!threads && firstSerial >= 0.0) {
            seconds = firstSerial;
            firstSerial = -1.0;
        }
        choice.record(threads, seconds);
        used.push_back(threads);
    }
    return used;
}

int countOf(const vector<bool>& used, bool threads, size_t from = 0) {
    int count = 0;
    for (size_t i = from; i < used.size(); i++)
        count += (used[i] == threads ? 1 : 0);
    return count;
}

/** The number of probes of a losing way in `runs` runs: intervals FirstProbeInterval, twice that, ... up to LastProbeInterval. */
int expectedProbes(int runs) {
    int probes = 0, interval = ThreadedLoopChoice::FirstProbeInterval;
    for (int run = interval; run <= runs; run += interval) {
        probes++;
        interval = min(2*interval, ThreadedLoopChoice::LastProbeInterval);
    }
    return probes;
}

void testChoiceSettles() {
    // Serial much faster (the CPU pool's 80 us round trip against a 1 us loop): serial first, then
    // the threads once, then serially but for the probes, whose intervals double.
    ThreadedLoopChoice cheap;
    vector<bool> used = drive(cheap, 20000, 1e-6, 8e-5);
    check(!used[0] && used[1], "the first run is serial and the second threaded");
    const int probes = expectedProbes(20000 - 2);
    check(countOf(used, true) >= probes && countOf(used, true) <= 1 + probes + 1,
          describe("a loop that is faster serially ran on the threads this many times in 20000 runs: ", countOf(used, true)));
    check(countOf(used, true, 10000) >= 2, "the threads are still probed late in the run");

    // The threads much faster (a large system).
    ThreadedLoopChoice large;
    used = drive(large, 20000, 1e-3, 2.6e-4);
    check(countOf(used, false) <= 1 + expectedProbes(20000) + 1,
          describe("a loop that is faster on the threads ran serially this many times in 20000 runs: ", countOf(used, false)));
    check(countOf(used, false, 10000) >= 2, "serial runs are still probed late in the run");
}

void testChoiceFollowsLoad() {
    // A change of conditions (another program starts, or stops): within one longest probe interval
    // the choice turns to the way that is now faster, and stays there.
    ThreadedLoopChoice choice;
    drive(choice, 30000, 1e-6, 8e-5);
    vector<bool> used = drive(choice, 30000, 1e-3, 5e-4);
    const int lateSerial = countOf(used, false, ThreadedLoopChoice::LastProbeInterval + 1);
    check(countOf(used, false) <= ThreadedLoopChoice::LastProbeInterval + expectedProbes(30000) + 1,
          describe("after the threads became faster the loop still ran serially this many times: ", countOf(used, false)));
    check(lateSerial <= expectedProbes(30000), describe("serial runs after the switch: ", lateSerial));
    used = drive(choice, 30000, 1e-6, 8e-5);
    check(countOf(used, true, ThreadedLoopChoice::LastProbeInterval + 1) <= expectedProbes(30000),
          "after serial runs became faster again the loop did not go back to them");
}

void testChoiceOutlier() {
    // One slow first serial run (the process was descheduled) makes the threads look faster; the
    // first probe, FirstProbeInterval runs later, corrects it.
    ThreadedLoopChoice choice;
    vector<bool> used = drive(choice, 200, 1e-5, 5e-5, 1e-3);
    check(used[1] && used[2], "after a slow serial run the threads are preferred");
    check(countOf(used, true, ThreadedLoopChoice::FirstProbeInterval + 3) <= expectedProbes(200),
          describe("the loop kept using the threads after one slow serial run: ", countOf(used, true)));
}

/** Four "threads" that run one after another in the caller: the split into ranges without concurrency. */
class SequentialThreads : public HostThreads {
public:
    int getNumThreads() const override {
        return 4;
    }
    void execute(const std::function<void(int thread)>& task) override {
        calls++;
        for (int thread = 0; thread < 4; thread++)
            task(thread);
    }
    int calls = 0;
};

/** `count` rigid waters (three constraints each) at random orientations on a lattice 0.31 nm apart, and 3 free particles. */
System waters(int count, vector<Vec3>& positions, mt19937& random) {
    System system;
    const Vec3 geometry[3] = {Vec3(0, 0, 0), Vec3(0.09572, 0, 0), Vec3(-0.0239988, 0.0926627, 0)};
    normal_distribution<double> normal;
    for (int i = 0; i < count; i++) {
        const Vec3 site(0.31*(i%9), 0.31*((i/9)%9), 0.31*(i/81));
        // A random rotation: the orthonormalized columns of a Gaussian matrix.
        Vec3 a(normal(random), normal(random), normal(random)), b(normal(random), normal(random), normal(random));
        a /= sqrt(a.dot(a));
        b -= a*a.dot(b);
        b /= sqrt(b.dot(b));
        const Vec3 c = a.cross(b);
        const int first = system.getNumParticles();
        for (int k = 0; k < 3; k++) {
            system.addParticle(k == 0 ? 15.999 : 1.008);
            positions.push_back(site + a*geometry[k][0] + b*geometry[k][1] + c*geometry[k][2]);
        }
        system.addConstraint(first, first + 1, 0.09572);
        system.addConstraint(first, first + 2, 0.09572);
        system.addConstraint(first + 1, first + 2, 0.15139);
    }
    for (int i = 0; i < 3; i++) {
        system.addParticle(39.948);
        positions.push_back(Vec3(-1.0 - i, 0, 0));
    }
    return system;
}

/** A force that depends on the positions, so that the trajectories go somewhere: a harmonic pull to the origin and a twist about z. */
void computeForces(const vector<Vec3>& positions, vector<Vec3>& forces) {
    forces.resize(positions.size());
    for (size_t i = 0; i < positions.size(); i++)
        forces[i] = positions[i]*(-50.0) + Vec3(-positions[i][1], positions[i][0], 0.0)*(80.0*(i%3));
}

bool sameBits(const vector<Vec3>& a, const vector<Vec3>& b) {
    return a.size() == b.size() && memcmp(a.data(), b.data(), a.size()*sizeof(Vec3)) == 0;
}

void testStagesOnThreads() {
    // 501 bodies: each of the four ranges holds 125 or 126, so groups of RigidLanes are cut short.
    mt19937 random(11);
    vector<Vec3> start;
    const System system = waters(501, start, random);
    normal_distribution<double> normal;
    vector<Vec3> startVelocities(start.size());
    for (Vec3& v : startVelocities)
        v = Vec3(normal(random), normal(random), normal(random));
    RigidBodySystem serialBodies(system, vector<vector<int> >(), false, "RigidBodyIntegrator");
    RigidBodySystem pooledBodies(system, vector<vector<int> >(), false, "RigidBodyIntegrator");
    SequentialThreads pool;
    RigidBodyDynamics serial(serialBodies, NULL, NULL), pooled(pooledBodies, &pool, NULL);
    vector<Vec3> positions[2] = {start, start}, velocities[2] = {startVelocities, startVelocities}, forces;
    RigidBodyDynamics* dynamics[2] = {&serial, &pooled};
    for (int k = 0; k < 2; k++)
        dynamics[k]->project(positions[k], velocities[k]);
    const double dt = 0.002;
    for (int step = 0; step < 40; step++) {
        for (int k = 0; k < 2; k++) {
            RigidBodyOptions::RotationMethod method = (step%2 == 0 ? RigidBodyOptions::Exact : RigidBodyOptions::NoSquish);
            computeForces(positions[k], forces);
            dynamics[k]->kickAndDrift(positions[k], velocities[k], forces, 0.5*dt, dt, method, 1e-6);
            computeForces(positions[k], forces);
            dynamics[k]->closingKick(positions[k], velocities[k], forces, 0.5*dt, 1e-6);
            dynamics[k]->thermalize(positions[k], velocities[k], 0.99, 2.5, 17, step, 1e-6);
            dynamics[k]->writeBodyVelocities(positions[k], velocities[k]);
        }
        check(sameBits(positions[0], positions[1]), describe("positions on the threads differ from the serial ones at step ", step));
        check(sameBits(velocities[0], velocities[1]), describe("velocities on the threads differ from the serial ones at step ", step));
    }
    // Each of the four stages ran on the threads at least at its second run.
    check(pool.calls >= 4, describe("the stages ran on the threads only this many times: ", pool.calls));
    check(sqrt((positions[0][0] - start[0]).dot(positions[0][0] - start[0])) > 1e-3, "the bodies moved");
}

void testArraysOnThreads() {
    mt19937 random(3);
    vector<Vec3> start;
    const System system = waters(4, start, random);
    RigidBodySystem bodies(system, vector<vector<int> >(), false, "RigidBodyIntegrator");
    SequentialThreads pool;
    RigidBodyDynamics dynamics(bodies, &pool, NULL);
    const int size = 6001;
    vector<Vec3> a(size);
    for (int i = 0; i < size; i++)
        a[i] = Vec3(i, 0.5*i, -i);
    vector<Vec3> copy;
    int threadedCopies = 0, threadedComparisons = 0;
    for (int run = 0; run < 60; run++) {
        int calls = pool.calls;
        dynamics.copyParticleArray(a, copy);
        threadedCopies += pool.calls - calls;
        check(sameBits(a, copy), describe("a copy differs from its original at run ", run));
        // A difference in each thread's range, at its first and last element.
        const int where = vector<int>{0, 1499, 1500, 3000, 4499, 4500, size - 1}[run%7];
        vector<Vec3> changed = a;
        changed[where][1] += 1e-9;
        calls = pool.calls;
        const bool equalCopy = dynamics.particleArraysEqual(a, copy);
        const bool equalChanged = dynamics.particleArraysEqual(a, changed);
        threadedComparisons += pool.calls - calls;
        check(equalCopy, "an array compared unequal to its copy");
        check(!equalChanged, describe("a difference at particle ", where) + " was not found");
    }
    check(threadedCopies >= 1 && threadedComparisons >= 1, "the copies and comparisons ran on the threads at least once");
}

} // namespace

int main() {
    try {
        testChoiceSettles();
        testChoiceFollowsLoad();
        testChoiceOutlier();
        testStagesOnThreads();
        testArraysOnThreads();
    }
    catch (const std::exception& e) {
        std::cout << "exception: " << e.what() << std::endl;
        return 1;
    }
    std::cout << "Done" << std::endl;
    return 0;
}
