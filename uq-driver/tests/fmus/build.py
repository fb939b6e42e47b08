#!/usr/bin/env python3
"""Builds railuq's C test FMUs (never shipped) and packs each as OUT_DIR/<modelName>.fmu.

    python3 uq-driver/tests/fmus/build.py target/test-fmu [--headers DIR] [--only NAME ...]

Every folder beside this script that holds a modelDescription.xml is one FMU: its *.c files and
common/*.c are compiled with $CC (default cc) against the FMI 2.0 headers into
binaries/linux64/<modelIdentifier>.so, and its resources/ folder (if any) is packed as is. The
headers come from --headers, else $FMI2_HEADERS, else the c-code folder of the installed fmpy.
The Rust tests build the same FMUs the same way (uq-driver/tests/support/test_fmus.rs).

Exit status 0 when every FMU was built; compiler warnings are printed (and returned by build()).
Only the Python standard library is needed.
"""
import argparse
import os
import pathlib
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET
import zipfile

HERE = pathlib.Path(__file__).resolve().parent
COMMON = HERE / "common"
CFLAGS = ["-std=c99", "-Wall", "-Wextra", "-pedantic", "-O2", "-shared", "-fPIC",
          "-fvisibility=hidden"]


class BuildError(Exception):
    pass


def find_headers(explicit=None):
    """The folder holding fmi2Functions.h."""
    candidates = []
    if explicit:
        candidates.append(pathlib.Path(explicit))
    elif os.environ.get("FMI2_HEADERS"):
        candidates.append(pathlib.Path(os.environ["FMI2_HEADERS"]))
    else:
        try:
            import fmpy  # noqa: PLC0415 (optional: only to find its headers)
        except ImportError as e:
            raise BuildError("no FMI 2.0 headers: pass --headers, set FMI2_HEADERS or install "
                             "fmpy") from e
        candidates.append(pathlib.Path(fmpy.__file__).parent / "c-code")
    for dir in candidates:
        if (dir / "fmi2Functions.h").is_file():
            return dir
    raise BuildError(f"{candidates[0]} has no fmi2Functions.h")


def fmu_folders():
    """The FMU folders beside this script, by name."""
    return sorted(p.parent for p in HERE.glob("*/modelDescription.xml"))


def read_names(folder):
    """(modelName, modelIdentifier) from the folder's modelDescription.xml."""
    root = ET.parse(folder / "modelDescription.xml").getroot()
    cs = root.find("CoSimulation")
    if cs is None:
        raise BuildError(f"{folder}: no CoSimulation element")
    return root.get("modelName"), cs.get("modelIdentifier")


def compile_binary(folder, identifier, headers, out, cc):
    """Compiles the folder's C files with the common layer into the shared library `out`;
    returns the compiler's diagnostics (empty when clean)."""
    sources = sorted(COMMON.glob("*.c")) + sorted(folder.glob("*.c"))
    cmd = [cc, *CFLAGS, "-I", str(headers), "-I", str(COMMON),
           *map(str, sources), "-o", str(out), "-lm"]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise BuildError(f"compiling {identifier} failed:\n{' '.join(cmd)}\n{proc.stderr}")
    return proc.stderr


def pack(folder, identifier, binary, fmu):
    """Writes the .fmu (deflate, forward slashes, files only) atomically. The archive carries a
    fixed date, so that the same sources give the same bytes: a second build (another test
    process building at the same time) replaces the file with an identical one, and a study
    that checks the FMU's SHA-256 on resuming sees no change."""
    partial = fmu.with_name(f".{fmu.name}.{os.getpid()}")
    with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as z:
        def add(path, name):
            info = zipfile.ZipInfo(name, date_time=(1980, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = (0o755 if name.endswith(".so") else 0o644) << 16
            z.writestr(info, path.read_bytes())

        add(folder / "modelDescription.xml", "modelDescription.xml")
        add(binary, f"binaries/linux64/{identifier}.so")
        resources = folder / "resources"
        for path in sorted(resources.rglob("*")) if resources.is_dir() else []:
            if path.is_file():
                add(path, "resources/" + path.relative_to(resources).as_posix())
    os.replace(partial, fmu)


def build(out_dir, headers=None, only=None, cc=None):
    """Builds every test FMU (or those named in `only`) into out_dir. Returns
    {modelName: (path of the .fmu, compiler diagnostics)}."""
    headers = find_headers(headers)
    cc = cc or os.environ.get("CC", "cc")
    out_dir = pathlib.Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    built = {}
    for folder in fmu_folders():
        name, identifier = read_names(folder)
        if only and name not in only:
            continue
        with tempfile.TemporaryDirectory() as tmp:
            binary = pathlib.Path(tmp) / f"{identifier}.so"
            diagnostics = compile_binary(folder, identifier, headers, binary, cc)
            fmu = out_dir / f"{name}.fmu"
            pack(folder, identifier, binary, fmu)
        built[name] = (fmu, diagnostics)
    missing = set(only or ()) - set(built)
    if missing:
        raise BuildError(f"no test FMU named {', '.join(sorted(missing))}")
    return built


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out_dir")
    parser.add_argument("--headers", help="folder with fmi2Functions.h")
    parser.add_argument("--only", nargs="+", metavar="NAME", help="model names to build")
    args = parser.parse_args(argv)
    try:
        built = build(args.out_dir, args.headers, args.only)
    except BuildError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    for name, (fmu, diagnostics) in built.items():
        if diagnostics:
            print(diagnostics, file=sys.stderr)
        print(f"{name}: {fmu}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
