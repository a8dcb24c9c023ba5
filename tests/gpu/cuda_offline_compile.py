"""Compile the common-compute kernel files for CUDA without a GPU, as OpenMM's CUDA platform would.

CudaContext::compileProgram (OpenMM 8.6.1) hands NVRTC one source: its compilation defines (precision,
math functions, warp primitives, periodic boundary macros), the real/mixed typedefs, the CUDA
platform's common header (common.cu: KERNEL, GLOBAL, DEVICE, ...), the kernel's own defines, then
vectorOps.cu and the kernel source, compiled with -arch=compute_XX --use_fast_math. This script
builds the same text for each kernel file in single, mixed and double precision, with the kernel
source being the numerics core (its common prelude and the core files, in order) followed by the
kernel file, as the plugin encodes them. common.cu and vectorOps.cu are read out of the installed
libOpenMMCUDA.so, so they are exactly the ones of the OpenMM that will compile the kernels.

Each source is compiled to a cubin for sm_90 (Hopper) by default: the whole back end, ptxas included,
where OpenMM asks NVRTC for compute_90 PTX and leaves the assembly to the driver. Any failed
compilation fails the script. No driver or GPU is needed: NVRTC is a library.

    python cuda_offline_compile.py --openmm-cuda <libOpenMMCUDA.so> --nvrtc <libnvrtc.so.13>
        --core <CorePreludeCommon.h> <CoreBasics.h> ... --kernels <kernels/*.cc> [--define NAME=VALUE ...]
        [--arch sm_90 compute_90 ...] [--ptxas-verbose]

With --ptxas-verbose, ptxas's report of each kernel (registers, stack frame, spill stores and loads)
is printed under its compilation.
"""

import argparse
import ctypes
import os
import re
import sys
import time

PRECISIONS = ("single", "mixed", "double")


def embeddedString(blob, marker):
    """The NUL-terminated string in blob that contains marker (exactly once)."""
    position = blob.find(marker)
    if position < 0 or blob.find(marker, position + 1) >= 0:
        raise RuntimeError(f"expected exactly one string containing {marker!r} in libOpenMMCUDA.so")
    return blob[blob.rfind(b"\0", 0, position) + 1:blob.find(b"\0", position)].decode()


def platformHeaders(openmmCuda):
    """CudaKernelSources::common and ::vectorOps, from the library's read-only data."""
    with open(openmmCuda, "rb") as library:
        blob = library.read()
    common = embeddedString(blob, b"This file contains CUDA definitions for the macros and functions needed for the")
    vectorOps = embeddedString(blob, b"This file defines vector operations to simplify code elsewhere.")
    if '#define KERNEL extern "C" __global__' not in common:
        raise RuntimeError("libOpenMMCUDA.so's common.cu does not define KERNEL as expected")
    return common, vectorOps


def compilationDefines(precision):
    """CudaContext's compilationDefines for a rectangular box and a driver of CUDA 9 or later."""
    double = precision == "double"
    real = "double" if double else "float"
    mixed = "float" if precision == "single" else "double"
    defines = {
        "SYNC_WARPS": "__syncwarp();",
        "SHFL(var, srcLane)": "__shfl_sync(0xffffffff, var, srcLane);",
        "BALLOT(var)": "__ballot_sync(0xffffffff, var);",
        "RECIP": "1.0/" if double else "1.0f/",
        "APPLY_PERIODIC_TO_DELTA(delta)": "{" + "".join(
            f"delta.{c} -= floor(delta.{c}*invPeriodicBoxSize.{c}+0.5f)*periodicBoxSize.{c}; \\\n" for c in "xyz")[:-3] + "}",
        "APPLY_PERIODIC_TO_POS(pos)": "{" + "".join(
            f"pos.{c} -= floor(pos.{c}*invPeriodicBoxSize.{c})*periodicBoxSize.{c}; \\\n" for c in "xyz")[:-3] + "}",
        "APPLY_PERIODIC_TO_POS_WITH_CENTER(pos, center)": "{" + "".join(
            f"pos.{c} -= floor((pos.{c}-center.{c})*invPeriodicBoxSize.{c}+0.5f)*periodicBoxSize.{c}; \\\n"
            for c in "xyz")[:-3] + "}",
    }
    if precision == "double":
        defines["USE_DOUBLE_PRECISION"] = "1"
    elif precision == "mixed":
        defines["USE_MIXED_PRECISION"] = "1"
    for n in "234":
        defines[f"make_real{n}"] = f"make_{real}{n}"
        defines[f"make_mixed{n}"] = f"make_{mixed}{n}"
    for function in ("sqrt", "rsqrt", "exp", "log", "pow", "cos", "sin", "tan", "acos", "asin", "atan",
                     "erf", "erfc", "fma", "fabs"):
        defines[function.upper()] = function if double else function + "f"
    return defines, real, mixed


def moduleSource(precision, common, vectorOps, kernelDefines, parts):
    """The text CudaContext::createModule gives NVRTC (its std::map writes the defines sorted), and
    where each of parts, (file name, text) pairs, begins in it: [(first line, file name)]."""
    defines, real, mixed = compilationDefines(precision)
    lines = [f"#define {name} {value}" for name, value in sorted(defines.items()) if name not in kernelDefines]
    lines.append("")
    lines += [f"typedef {real}{n} real{n};" for n in ("", "2", "3", "4")]
    lines += [f"typedef {mixed}{n} mixed{n};" for n in ("", "2", "3", "4")]
    lines += ["typedef unsigned int tileflags;", common]
    lines += [f"#define {name} {value}" for name, value in sorted(kernelDefines.items())]
    lines += ["", vectorOps]
    text = "\n".join(lines) + "\n"
    starts = []
    for name, partText in parts:
        starts.append((text.count("\n") + 1, name))
        text += partText + "\n"
    return text, starts


def readableLog(log, moduleName, starts):
    """The compiler's diagnostics, each with its file and line, without CUDA 13's deprecation of
    double4 and friends (OpenMM's own headers use them) and NVRTC's remarks about suppressing it."""
    kept = []
    for block in re.split(r"\n\s*\n", log):
        block = block.strip()
        if not block or block.startswith("Remark:") or re.search(r'"(u?longlong4|double4)" was declared deprecated', block):
            continue

        def locate(match):
            line = int(match.group(1))
            first, name = max(((first, name) for first, name in starts if first <= line), default=(1, "prelude"))
            return f"{name}:{line - first + 1}" if name != "prelude" else f"{moduleName}({line}, OpenMM's prelude)"
        kept.append(re.sub(re.escape(moduleName) + r"\((\d+)\)", locate, block))
    return "\n".join(kept)


class Nvrtc:
    def __init__(self, path):
        self.library = ctypes.CDLL(path)
        self.library.nvrtcGetErrorString.restype = ctypes.c_char_p
        major, minor = ctypes.c_int(), ctypes.c_int()
        self.check(self.library.nvrtcVersion(ctypes.byref(major), ctypes.byref(minor)), "nvrtcVersion")
        self.version = f"{major.value}.{minor.value}"

    def check(self, result, call):
        if result != 0:
            raise RuntimeError(f"{call}: {self.library.nvrtcGetErrorString(result).decode()}")

    def compile(self, source, name, options):
        """(success, size of the PTX or cubin, compiler log)."""
        program = ctypes.c_void_p()
        self.check(self.library.nvrtcCreateProgram(ctypes.byref(program), source.encode(), name.encode(), 0, None, None),
                   "nvrtcCreateProgram")
        try:
            encoded = [option.encode() for option in options]
            result = self.library.nvrtcCompileProgram(program, len(encoded), (ctypes.c_char_p * len(encoded))(*encoded))
            logSize = ctypes.c_size_t()
            self.check(self.library.nvrtcGetProgramLogSize(program, ctypes.byref(logSize)), "nvrtcGetProgramLogSize")
            log = ctypes.create_string_buffer(logSize.value)
            self.check(self.library.nvrtcGetProgramLog(program, log), "nvrtcGetProgramLog")
            size = ctypes.c_size_t()
            if result == 0:
                getSize = self.library.nvrtcGetCUBINSize if "-arch=sm_" in options[0] else self.library.nvrtcGetPTXSize
                self.check(getSize(program, ctypes.byref(size)), "nvrtcGet...Size")
            return result == 0, size.value, log.value.decode(errors="replace").strip()
        finally:
            self.library.nvrtcDestroyProgram(ctypes.byref(program))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--openmm-cuda", required=True, help="libOpenMMCUDA.so (OpenMM.libs/lib/plugins)")
    parser.add_argument("--nvrtc", required=True, help="libnvrtc.so.N (site-packages/nvidia/cu13/lib)")
    parser.add_argument("--core", nargs="*", default=[], help="the numerics core files, prelude first, in order")
    parser.add_argument("--kernels", nargs="+", required=True, help="the kernel files (kernels/*.cc)")
    parser.add_argument("--define", action="append", default=[], metavar="NAME=VALUE",
                        help="a define the plugin passes to compileProgram (repeatable)")
    parser.add_argument("--arch", nargs="+", default=["sm_90"],
                        help="NVRTC targets: sm_XX for a cubin, compute_XX for PTX (default sm_90)")
    parser.add_argument("--ptxas-verbose", action="store_true",
                        help="for sm_XX targets, have ptxas report each kernel's registers, stack and spills "
                             "(--ptxas-options=-v; OpenMM passes no options of a plugin's to NVRTC, so this is "
                             "how the register use of the kernels is seen)")
    arguments = parser.parse_args()

    common, vectorOps = platformHeaders(arguments.openmm_cuda)
    kernelDefines = dict(definition.partition("=")[::2] for definition in arguments.define)
    core = [(os.path.basename(path), open(path).read()) for path in arguments.core]
    nvrtc = Nvrtc(arguments.nvrtc)
    print(f"NVRTC {nvrtc.version}; {len(arguments.core)} core files; {len(kernelDefines)} kernel defines")

    failures = 0
    for kernel in arguments.kernels:
        name = os.path.basename(kernel)
        parts = core + [(name, open(kernel).read())]
        for precision in PRECISIONS:
            text, starts = moduleSource(precision, common, vectorOps, kernelDefines, parts)
            for architecture in arguments.arch:
                start = time.perf_counter()
                options = [f"-arch={architecture}", "--use_fast_math"]
                if arguments.ptxas_verbose and architecture.startswith("sm_"):
                    options.append("--ptxas-options=-v")
                ok, size, log = nvrtc.compile(text, name + ".cu", options)
                seconds = time.perf_counter() - start
                print(f"{name:<20} {precision:<7} {architecture:<11} {'ok' if ok else 'FAILED':<7}"
                      f"{size:>9} bytes {seconds:6.1f} s")
                message = readableLog(log, name + ".cu", starts)
                if message:
                    print("    " + message.replace("\n", "\n    "))
                failures += not ok
    compiled = len(arguments.kernels) * len(PRECISIONS) * len(arguments.arch)
    print(f"NVRTC: {compiled - failures} of {compiled} compilations succeeded")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
