"""The PEP 517 backend of the railuq package: maturin's, after putting the project's FMUs into
the package (``railuq/fmus/*.fmu``), so that the wheel ships them.

The FMUs come from ``$RAILUQ_WHEEL_FMUS`` when it names a folder of them (``make wheel`` sets
it to ``target/fmu``, so the wheel carries the very FMUs ``make test`` checks, win64 binary
included); otherwise they are built here: ``cargo build --release -p railuq`` and
``railuq-fmu package`` (linux64 only). Both steps reuse the workspace's ``target/``.

On x86-64 Linux every link goes through ``.cargo/zig-cc`` (zig, from the ``ziglang`` package
the build requires, linking against glibc 2.17) unless a linker is set already
(``CARGO_TARGET_X86_64_UNKNOWN_LINUX_GNU_LINKER``, as ``make`` sets it) or ``RAILUQ_ZIG=no``:
the wheel then loads on any Linux from glibc 2.17 on, whatever the build machine's glibc.

Everything else is maturin's: ``[tool.maturin]`` in pyproject.toml, and maturin's own
environment variables (``MATURIN_PEP517_ARGS``, ...).
"""
from __future__ import annotations

import json
import os
import platform
import shutil
import subprocess
import sys
from pathlib import Path

import maturin
from maturin import (  # noqa: F401  (the hooks this backend does not change)
    build_sdist,
    get_requires_for_build_editable,
    get_requires_for_build_sdist,
    get_requires_for_build_wheel,
    prepare_metadata_for_build_editable,
    prepare_metadata_for_build_wheel,
)

HERE = Path(__file__).resolve().parents[1]  # python/
ROOT = HERE.parent  # the workspace
PACKAGE_FMUS = HERE / "railuq" / "fmus"
MODELS = ("Wheel", "Bogie", "VehicleTrack", "Vehicle")


def _say(message: str) -> None:
    print(f"railuq build: {message}", file=sys.stderr, flush=True)


def _target_dir(cargo: str) -> Path:
    meta = subprocess.run(
        [cargo, "metadata", "--format-version", "1", "--no-deps"],
        cwd=ROOT, check=True, stdout=subprocess.PIPE, text=True,
    )
    return Path(json.loads(meta.stdout)["target_directory"])


def _built_fmus(work: Path) -> Path:
    """Builds the FMU library and the packaging tool, and packages the FMUs into work/."""
    cargo = os.environ.get("CARGO", "cargo")
    cmd = [cargo, "build", "--release", "-p", "railuq", "--lib", "--bin", "railuq-fmu"]
    _say(" ".join(cmd))
    subprocess.run(cmd, cwd=ROOT, check=True, stdout=sys.stderr)
    release = _target_dir(cargo) / "release"
    cmd = [str(release / "railuq-fmu"), "package", str(release / "librailuq.so"), str(work)]
    _say(" ".join(cmd))
    subprocess.run(cmd, cwd=ROOT, check=True, stdout=sys.stderr)
    return work


LINKER = "CARGO_TARGET_X86_64_UNKNOWN_LINUX_GNU_LINKER"


def _zig_linker() -> None:
    """Links with zig against an old glibc (see the module's documentation), and tags the
    wheel for it."""
    zig_cc = str(ROOT / ".cargo" / "zig-cc")
    if LINKER not in os.environ and os.environ.get("RAILUQ_ZIG", "auto") != "no" \
            and sys.platform == "linux" and platform.machine() in ("x86_64", "AMD64"):
        try:
            import ziglang  # noqa: F401
        except ImportError:
            _say("no zig (the ziglang package): linking against the build machine's glibc")
        else:
            os.environ[LINKER] = zig_cc
            os.environ.setdefault("RAILUQ_ZIG_PYTHON", sys.executable)
            _say(f"linking with zig against glibc {os.environ.get('RAILUQ_GLIBC', '2.17')}")
    # The wheel's tag says what it needs (maturin checks the module's symbol versions against
    # it): manylinux2014 is glibc 2.17. Only for zig's default floor: another RAILUQ_GLIBC, or
    # another linker, gets maturin's own judgement.
    linker = os.environ.get(LINKER)
    zig_linked = linker is not None and Path(linker).resolve() == Path(zig_cc).resolve()
    if zig_linked and os.environ.get("RAILUQ_GLIBC", "2.17") == "2.17":
        args = os.environ.get("MATURIN_PEP517_ARGS", "")
        if "--compatibility" not in args and "--manylinux" not in args:
            os.environ["MATURIN_PEP517_ARGS"] = (args + " --compatibility manylinux2014").strip()


def _put_fmus() -> None:
    given = os.environ.get("RAILUQ_WHEEL_FMUS")
    if given:
        source = Path(given)
        missing = [m for m in MODELS if not (source / f"{m}.fmu").is_file()]
        if missing:
            raise RuntimeError(f"RAILUQ_WHEEL_FMUS={given}: no {', '.join(missing)}.fmu there "
                               "(build them with `make fmu`)")
    else:
        source = _built_fmus(HERE / "build_backend" / "fmus.tmp")
    if PACKAGE_FMUS.exists():
        shutil.rmtree(PACKAGE_FMUS)
    PACKAGE_FMUS.mkdir(parents=True)
    for m in MODELS:
        shutil.copy2(source / f"{m}.fmu", PACKAGE_FMUS / f"{m}.fmu")
    _say(f"the package ships {', '.join(MODELS)} from {source}")


def build_wheel(wheel_directory, config_settings=None, metadata_directory=None):
    _zig_linker()
    _put_fmus()
    return maturin.build_wheel(wheel_directory, config_settings, metadata_directory)


def build_editable(wheel_directory, config_settings=None, metadata_directory=None):
    _zig_linker()
    _put_fmus()
    return maturin.build_editable(wheel_directory, config_settings, metadata_directory)
