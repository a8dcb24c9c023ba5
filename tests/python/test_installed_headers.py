"""The C++ API of the installed wheel: a program built only against site-packages (the headers the
wheel installs under openmmrigid/include, libOpenMMRigid.so beside them, OpenMM's own headers and
library in OpenMM.libs) creates a RigidBodyIntegrator, loads the Reference kernels as the README
says, and steps a rigid water; it must report the body it found and a conserved constraint geometry."""

import os
import shutil
import subprocess
from pathlib import Path

import openmm
import pytest

import openmmrigid

PROGRAM = r"""
#include "RigidBodyIntegrator.h"
#include "openmm/Context.h"
#include "openmm/Platform.h"
#include "openmm/System.h"
#include "openmm/Vec3.h"
#include <cmath>
#include <iostream>
#include <vector>

int main(int argc, char* argv[]) {
    OpenMM::Platform::loadPluginLibrary(argv[1]);
    OpenMM::System system;
    system.addParticle(15.999);
    system.addParticle(1.008);
    system.addParticle(1.008);
    system.addConstraint(0, 1, 0.09572);
    system.addConstraint(0, 2, 0.09572);
    system.addConstraint(1, 2, 0.15139);
    OpenMMRigid::RigidBodyIntegrator integrator(0.002);
    OpenMM::Context context(system, integrator, OpenMM::Platform::getPlatformByName("Reference"));
    context.setPositions({OpenMM::Vec3(0, 0, 0), OpenMM::Vec3(0.09572, 0, 0), OpenMM::Vec3(-0.02399, 0.09267, 0)});
    context.setVelocities({OpenMM::Vec3(0.1, 0, 0), OpenMM::Vec3(0, 2.0, 0), OpenMM::Vec3(0, 0, 2.0)});
    integrator.step(100);
    std::vector<OpenMM::Vec3> x = context.getState(OpenMM::State::Positions).getPositions();
    OpenMM::Vec3 d = x[1] - x[2];
    std::cout << integrator.getNumBodies() << " " << integrator.getBodyKind(0) << " " << std::sqrt(d.dot(d)) << std::endl;
    return 0;
}
"""


def test_a_cpp_program_builds_against_the_installed_wheel(tmp_path):
    compiler = shutil.which("c++") or shutil.which("g++")
    if compiler is None:
        pytest.skip("no C++ compiler")
    package = Path(openmmrigid.__file__).parent
    openmmLibs = Path(openmm.__file__).parent.parent / "OpenMM.libs"
    assert (package / "include" / "RigidBodyIntegrator.h").exists(), "the wheel installs no headers"
    source = tmp_path / "program.cpp"
    source.write_text(PROGRAM)
    executable = tmp_path / "program"
    subprocess.run([compiler, "-std=c++17", str(source), "-o", str(executable),
                    f"-I{package / 'include'}", f"-I{openmmLibs / 'include'}",
                    f"-L{package}", "-lOpenMMRigid", f"-L{openmmLibs / 'lib'}", "-lOpenMM",
                    f"-Wl,-rpath,{package}:{openmmLibs / 'lib'}"], check=True, capture_output=True, text=True)
    result = subprocess.run([str(executable), str(package / "libOpenMMRigidReference.so")], check=True,
                            capture_output=True, text=True, env=dict(os.environ))
    count, kind, distance = result.stdout.split()
    assert (count, kind) == ("1", "asymmetric")
    assert abs(float(distance) - 0.15139) < 1e-9
