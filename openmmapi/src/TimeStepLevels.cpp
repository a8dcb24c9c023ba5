#include "internal/TimeStepLevels.h"
#include "openmm/CMAPTorsionForce.h"
#include "openmm/CMMotionRemover.h"
#include "openmm/CustomAngleForce.h"
#include "openmm/CustomBondForce.h"
#include "openmm/CustomCompoundBondForce.h"
#include "openmm/CustomTorsionForce.h"
#include "openmm/HarmonicAngleForce.h"
#include "openmm/HarmonicBondForce.h"
#include "openmm/NonbondedForce.h"
#include "openmm/OpenMMException.h"
#include "openmm/PeriodicTorsionForce.h"
#include "openmm/RBTorsionForce.h"
#include "openmm/System.h"
#include "openmm/VirtualSite.h"
#include <algorithm>
#include <map>

using namespace OpenMM;
using namespace std;

namespace OpenMMRigid {

vector<TimeStepLevel> timeStepLevels(const vector<pair<int, int> >& groupSubsteps, int integrationGroups, const string& className) {
    if (groupSubsteps.empty())
        return vector<TimeStepLevel>{{integrationGroups, 1}};
    map<int, int> groupsOf;  // substeps -> groups
    int seen = 0;
    for (const pair<int, int>& entry : groupSubsteps) {
        const int group = entry.first, substeps = entry.second;
        if (group < 0 || group > 31)
            throw OpenMMException(className + ": force group " + to_string(group) + " is not a force group (0 to 31)");
        if (seen & (1 << group))
            throw OpenMMException(className + ": force group " + to_string(group) + " is listed twice in the substeps");
        if (substeps < 1)
            throw OpenMMException(className + ": force group " + to_string(group) + " has " + to_string(substeps) +
                    " substeps; each group is evaluated at least once per step");
        seen |= 1 << group;
        groupsOf[substeps] |= 1 << group;
    }
    vector<TimeStepLevel> levels;
    for (const pair<const int, int>& level : groupsOf) {
        if (levels.empty() && level.first != 1)
            throw OpenMMException(className + ": the slowest force groups have " + to_string(level.first) + " substeps; "
                    "give them 1 (the step is theirs) and the faster groups their multiples of it, or take a smaller step size");
        if (!levels.empty() && level.first % levels.back().substeps != 0)
            throw OpenMMException(className + ": " + to_string(level.first) + " substeps is not a multiple of " +
                    to_string(levels.back().substeps) + ", the next slower level's; each level divides the drifts of the one above");
        levels.push_back({level.second, level.first});
    }
    return levels;
}

namespace {

/** Marks the particles of each term of a per-term bonded Force; false for a Force that may act on any particle. */
bool markTerms(const Force& force, vector<char>& reached) {
    vector<int> particles;
    vector<double> parameters;
    auto mark = [&](initializer_list<int> list) {
        for (int p : list)
            reached[p] = 1;
    };
    if (const HarmonicBondForce* bonds = dynamic_cast<const HarmonicBondForce*>(&force)) {
        for (int i = 0; i < bonds->getNumBonds(); i++) {
            int a, b;
            double length, k;
            bonds->getBondParameters(i, a, b, length, k);
            mark({a, b});
        }
        return true;
    }
    if (const HarmonicAngleForce* angles = dynamic_cast<const HarmonicAngleForce*>(&force)) {
        for (int i = 0; i < angles->getNumAngles(); i++) {
            int a, b, c;
            double angle, k;
            angles->getAngleParameters(i, a, b, c, angle, k);
            mark({a, b, c});
        }
        return true;
    }
    if (const PeriodicTorsionForce* torsions = dynamic_cast<const PeriodicTorsionForce*>(&force)) {
        for (int i = 0; i < torsions->getNumTorsions(); i++) {
            int a, b, c, d, periodicity;
            double phase, k;
            torsions->getTorsionParameters(i, a, b, c, d, periodicity, phase, k);
            mark({a, b, c, d});
        }
        return true;
    }
    if (const RBTorsionForce* torsions = dynamic_cast<const RBTorsionForce*>(&force)) {
        for (int i = 0; i < torsions->getNumTorsions(); i++) {
            int a, b, c, d;
            double c0, c1, c2, c3, c4, c5;
            torsions->getTorsionParameters(i, a, b, c, d, c0, c1, c2, c3, c4, c5);
            mark({a, b, c, d});
        }
        return true;
    }
    if (const CMAPTorsionForce* cmap = dynamic_cast<const CMAPTorsionForce*>(&force)) {
        for (int i = 0; i < cmap->getNumTorsions(); i++) {
            int map, a1, a2, a3, a4, b1, b2, b3, b4;
            cmap->getTorsionParameters(i, map, a1, a2, a3, a4, b1, b2, b3, b4);
            mark({a1, a2, a3, a4, b1, b2, b3, b4});
        }
        return true;
    }
    if (const CustomBondForce* bonds = dynamic_cast<const CustomBondForce*>(&force)) {
        for (int i = 0; i < bonds->getNumBonds(); i++) {
            int a, b;
            bonds->getBondParameters(i, a, b, parameters);
            mark({a, b});
        }
        return true;
    }
    if (const CustomAngleForce* angles = dynamic_cast<const CustomAngleForce*>(&force)) {
        for (int i = 0; i < angles->getNumAngles(); i++) {
            int a, b, c;
            angles->getAngleParameters(i, a, b, c, parameters);
            mark({a, b, c});
        }
        return true;
    }
    if (const CustomTorsionForce* torsions = dynamic_cast<const CustomTorsionForce*>(&force)) {
        for (int i = 0; i < torsions->getNumTorsions(); i++) {
            int a, b, c, d;
            torsions->getTorsionParameters(i, a, b, c, d, parameters);
            mark({a, b, c, d});
        }
        return true;
    }
    if (const CustomCompoundBondForce* compound = dynamic_cast<const CustomCompoundBondForce*>(&force)) {
        for (int i = 0; i < compound->getNumBonds(); i++) {
            compound->getBondParameters(i, particles, parameters);
            for (int p : particles)
                reached[p] = 1;
        }
        return true;
    }
    return false;
}

/** Whether a part of the Force is evaluated with the groups (a NonbondedForce's reciprocal space may have a group of its own). */
bool inGroups(const Force& force, int groups) {
    if (groups & (1 << force.getForceGroup()))
        return true;
    const NonbondedForce* nonbonded = dynamic_cast<const NonbondedForce*>(&force);
    return nonbonded != NULL && nonbonded->getReciprocalSpaceForceGroup() >= 0 &&
           (groups & (1 << nonbonded->getReciprocalSpaceForceGroup()));
}

} // namespace

vector<char> particlesReachedBy(const System& system, int groups) {
    const int numParticles = system.getNumParticles();
    vector<char> reached(numParticles, 0);
    for (int f = 0; f < system.getNumForces(); f++) {
        const Force& force = system.getForce(f);
        if (!inGroups(force, groups))
            continue;
        if (!markTerms(force, reached)) {
            // A Force that may act on any particle. (A CMMotionRemover acts on velocities, not through forces.)
            if (dynamic_cast<const CMMotionRemover*>(&force) == NULL)
                return vector<char>(numParticles, 1);
        }
    }
    // A force on a virtual site is spread over the particles it is built from (recursively, for a
    // site built from sites: repeated until nothing changes).
    for (bool changed = true; changed;) {
        changed = false;
        for (int p = 0; p < numParticles; p++) {
            if (!reached[p] || !system.isVirtualSite(p))
                continue;
            const VirtualSite& site = system.getVirtualSite(p);
            for (int i = 0; i < site.getNumParticles(); i++) {
                const int parent = site.getParticle(i);
                if (!reached[parent]) {
                    reached[parent] = 1;
                    changed = true;
                }
            }
        }
    }
    return reached;
}

} // namespace OpenMMRigid
