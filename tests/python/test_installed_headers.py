"""The C++ API of the installed wheel: a program built only against site-packages (the headers the
wheel installs under openmmrigid/include, libOpenMMRigid.so beside them, OpenMM's own headers and
library in OpenMM.libs) creates a RigidBodyIntegrator and a RigidBodyBussiIntegrator, loads the
Reference kernels as docs/api/cpp.rst says, and steps a rigid water with each; it must report the body it
found, a conserved constraint geometry, and the temperature of the water's 6 degrees of freedom. The
wheel installs every public header of openmmapi/include."""

import os
import shutil
import subprocess
from pathlib import Path

import openmm
import openmm.unit as unit
import pytest

import openmmrigid

GAS_CONSTANT = unit.MOLAR_GAS_CONSTANT_R.value_in_unit(unit.kilojoule_per_mole / unit.kelvin)

PROGRAM = r"""
#include "RigidBodyBussiIntegrator.h"
#include "RigidBodyIntegrator.h"
#include "openmm/Context.h"
#include "openmm/Platform.h"
#include "openmm/System.h"
#include "openmm/Vec3.h"
#include <cmath>
#include <iomanip>
#include <iostream>
#include <vector>

void run(OpenMMRigid::RigidBodyIntegrator& integrator) {
    OpenMM::System system;
    system.addParticle(15.999);
    system.addParticle(1.008);
    system.addParticle(1.008);
    system.addConstraint(0, 1, 0.09572);
    system.addConstraint(0, 2, 0.09572);
    system.addConstraint(1, 2, 0.15139);
    OpenMM::Context context(system, integrator, OpenMM::Platform::getPlatformByName("Reference"));
    context.setPositions({OpenMM::Vec3(0, 0, 0), OpenMM::Vec3(0.09572, 0, 0), OpenMM::Vec3(-0.02399, 0.09267, 0)});
    context.setVelocities({OpenMM::Vec3(0.1, 0, 0), OpenMM::Vec3(0, 2.0, 0), OpenMM::Vec3(0, 0, 2.0)});
    integrator.step(100);
    OpenMM::State state = context.getState(OpenMM::State::Positions | OpenMM::State::Energy);
    std::vector<OpenMM::Vec3> x = state.getPositions();
    OpenMM::Vec3 d = x[1] - x[2];
    std::cout << std::setprecision(17) << integrator.getNumBodies() << " " << integrator.getBodyParticles(0).size() << " "
              << std::sqrt(d.dot(d)) << " " << state.getKineticEnergy() << " " << integrator.computeSystemTemperature()
              << " " << (integrator.getMeasureShadowWork() ? integrator.getHeat() : 0.0) << std::endl;
}

int main(int argc, char* argv[]) {
    OpenMM::Platform::loadPluginLibrary(argv[1]);
    OpenMMRigid::RigidBodyIntegrator constantEnergy(0.002);
    run(constantEnergy);
    OpenMMRigid::RigidBodyBussiIntegrator bussi(300.0, 0.01, 0.002);
    bussi.setRandomNumberSeed(5);
    bussi.setMeasureShadowWork(true);
    run(bussi);
    std::cout << std::setprecision(17) << bussi.getTemperature() << std::endl;
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
    lines = result.stdout.splitlines()
    assert len(lines) == 3, result.stdout
    kinetic, heats = [], []
    for line in lines[:2]:
        count, size, distance, kineticEnergy, temperature, heat = line.split()
        heats.append(float(heat))
        assert (count, size) == ("1", "3")
        assert abs(float(distance) - 0.15139) < 1e-9
        # One rigid water: 6 degrees of freedom (3 translational, 3 rotational).
        assert float(temperature) == pytest.approx(2 * float(kineticEnergy) / (6 * GAS_CONSTANT), rel=1e-9)
        kinetic.append(float(kineticEnergy))
    assert float(lines[2]) == 300.0
    # The thermostat (tau 0.01 ps: 20 relaxation times) changed the kinetic energy, and measured the heat.
    assert heats[1] != 0.0 and kinetic[1] != pytest.approx(kinetic[0], rel=1e-6)


def test_the_public_headers_are_installed():
    """Every header of openmmapi/include (the public API, RigidBodyBussiIntegrator.h among them) is in
    the wheel's include folder."""
    installed = Path(openmmrigid.__file__).parent / "include"
    for name in ("RigidBodyIntegratorBase.h", "RigidBodyIntegrator.h", "RigidBodyBussiIntegrator.h",
                 "RigidBodyLangevinIntegrator.h", "RigidBodyOptions.h", "PlatformSupport.h"):
        assert (installed / name).exists(), f"the wheel does not install {name}"
    source = Path(__file__).resolve().parents[2] / "openmmapi" / "include"
    if source.is_dir():
        missing = [str(header.relative_to(source)) for header in source.rglob("*.h")
                   if not (installed / header.relative_to(source)).exists()]
        assert not missing, f"headers of openmmapi/include the wheel does not install: {missing}"
    # The Bussi integrator's header is complete on its own: its base and the export macro come with it.
    text = (installed / "RigidBodyBussiIntegrator.h").read_text()
    assert "class OPENMM_EXPORT_RIGID RigidBodyBussiIntegrator : public RigidBodyIntegrator" in text
