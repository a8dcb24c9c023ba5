#ifndef OPENMMRIGID_TIMESTEPLEVELS_H_
#define OPENMMRIGID_TIMESTEPLEVELS_H_

#include "internal/windowsExportRigid.h"
#include <string>
#include <utility>
#include <vector>

namespace OpenMM {
class System;
}

namespace OpenMMRigid {

/**
 * One level of a multiple-time-step nest (RigidBodyIntegratorBase::setForceGroupSubsteps()): the
 * force groups it kicks with, as a bit mask, and how many times per step they are evaluated. Level 0
 * is the step itself (substeps 1); each inner level divides every drift of the level above into
 * substeps / (the level above's substeps) equal parts, kicking with its own forces around them.
 */
struct TimeStepLevel {
    int groups;
    int substeps;
};

/**
 * The levels of OpenMM's MTS convention, a list of (force group, substeps) pairs (MTSLangevinIntegrator's
 * `groups`), slowest first: groups with the same number of substeps share a level (their kicks are at the
 * same positions, so they are evaluated together). An empty list is one level of every integration force
 * group (integrationGroups), today's step.
 *
 * @throws OpenMMException naming className if a group is outside 0 to 31 or listed twice, a number of
 *         substeps is below 1, the slowest groups' is not 1, or a level's is not a multiple of the one above
 */
OPENMM_EXPORT_RIGID std::vector<TimeStepLevel> timeStepLevels(const std::vector<std::pair<int, int> >& groupSubsteps,
                                                              int integrationGroups, const std::string& className);

/**
 * For each particle, whether a Force in one of the groups (a bit mask) can exert a force on it: the
 * particles of the bonded terms of the Forces OpenMM defines per term (harmonic bonds, angles,
 * torsions, CMAP, the custom bonded forces), and every particle for any other Force (nonbonded,
 * external, a plugin's). A force on a virtual site reaches the particles it is built from.
 */
OPENMM_EXPORT_RIGID std::vector<char> particlesReachedBy(const OpenMM::System& system, int groups);

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_TIMESTEPLEVELS_H_*/
