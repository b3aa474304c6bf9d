"""Compile CasADi functions to a shared library once and cache it on disk.

The library is keyed by the model structure (body count, joints, outputs — see
:attr:`SystemBuilder.structure_key`), the CasADi version and this module's code version;
parameters and constants are function inputs, so every run and every worker process with
the same structure loads the same file instead of recompiling (it is compiled once: a
process that needs it meanwhile waits on its ``.lock`` file).  The cache directory is
``$FUZZYGAIT_CACHE_DIR`` or ``~/.cache/fuzzygait``.  Without a C compiler (or with
``FUZZYGAIT_NO_COMPILE=1``) the functions run in CasADi's virtual machine: same numbers,
slower.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
import time
import warnings
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

import casadi as ca

CODE_VERSION = "1"


def cache_dir() -> Path:
    """Directory of the compiled libraries."""
    root = os.environ.get("FUZZYGAIT_CACHE_DIR")
    return Path(root) if root else Path.home() / ".cache" / "fuzzygait"


def compiler() -> str | None:
    """The C compiler to use, or None (compilation disabled or none found)."""
    if os.environ.get("FUZZYGAIT_NO_COMPILE", "") not in ("", "0"):
        return None
    return os.environ.get("CC") or shutil.which("gcc") or shutil.which("cc") or shutil.which("clang")


def library_key(structure_key: str, names: Sequence[str]) -> str:
    version = ca.__version__  # type: ignore[attr-defined]  # set at import, absent from casadi's stub
    text = "|".join([CODE_VERSION, version, structure_key, *names])
    return hashlib.sha256(text.encode()).hexdigest()[:20]


def cached_library(structure_key: str, names: Sequence[str]) -> Path:
    return cache_dir() / f"fg_{library_key(structure_key, names)}.so"


def load_cached(structure_key: str, names: Sequence[str]) -> dict[str, ca.Function] | None:
    """The compiled functions of this structure if a library is cached, else None."""
    path = cached_library(structure_key, names)
    if compiler() is None or not path.exists():
        return None
    return {name: ca.external(name, str(path)) for name in names}


def compile_functions(
    structure_key: str, functions: Sequence[ca.Function], optimisation: str = "-O1"
) -> dict[str, ca.Function]:
    """Compile ``functions`` into one cached shared library and load them from it.

    Falls back to the given (virtual-machine) functions with a warning when no compiler is
    available or compilation fails.
    """
    names = [f.name() for f in functions]
    cached = load_cached(structure_key, names)
    if cached is not None:
        return cached
    target = build_library(cached_library(structure_key, names), functions, optimisation=optimisation)
    if target is None:
        return {f.name(): f for f in functions}
    return {name: ca.external(name, str(target)) for name in names}


def build_library(target: Path, functions: Sequence[ca.Function], sources: Sequence[Path] = (),
                  optimisation: str = "-O1", header: str | None = None,
                  purpose: str = "the simulator's generated code") -> Path | None:  # fmt: skip
    """Generate C code for ``functions``, compile it with the C files ``sources`` into the
    shared library ``target`` (written atomically) and return ``target``; None (with a
    warning naming ``purpose``) without a compiler or when compilation fails.
    ``header``: the generated file's base name, for sources that include ``<header>.h``."""
    cc = compiler()
    if cc is None:
        return None
    target.parent.mkdir(parents=True, exist_ok=True)
    _sweep_stale_builds(target.parent)
    with _compiling(target):
        if target.exists():  # another process compiled it while this one waited
            return target
        return _build(cc, target, functions, sources, optimisation, header, purpose)


#: Age (s) past which a build folder left in the cache (its process killed mid-build) is removed.
STALE_BUILD_SECONDS = 3600.0


def _sweep_stale_builds(folder: Path) -> None:
    """Remove the build folders (``tmp*``) older than :data:`STALE_BUILD_SECONDS` that a
    killed process left in the cache ``folder``; a build in progress is younger."""
    now = time.time()
    for stale in folder.glob("tmp*"):
        try:
            if stale.is_dir() and now - stale.stat().st_mtime > STALE_BUILD_SECONDS:
                shutil.rmtree(stale, ignore_errors=True)
        except OSError:
            continue


@contextmanager
def _compiling(target: Path) -> Iterator[None]:
    """Hold the lock file beside ``target`` while it is compiled, so that processes
    needing the same library at once (the workers of a pool on a fresh machine) compile
    it once and the others wait for it.  An advisory ``flock``: released when its holder
    ends, however it ends; without ``fcntl`` (Windows) no lock (each compiles, and the
    atomic rename keeps the file whole)."""
    try:
        import fcntl
    except ImportError:
        yield
        return
    with open(target.with_name(target.name + ".lock"), "a") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)


def _build(cc: str, target: Path, functions: Sequence[ca.Function], sources: Sequence[Path], optimisation: str,
           header: str | None, purpose: str) -> Path | None:  # fmt: skip
    """Generate, compile and move into place (:func:`build_library`, under its lock)."""
    with tempfile.TemporaryDirectory(dir=target.parent) as tmp:
        base = header or target.stem
        generator = ca.CodeGenerator(f"{base}.c", {"with_header": header is not None})
        for f in functions:
            generator.add(f)
        generator.generate(tmp + os.sep)
        library = Path(tmp) / "lib.so"
        command = [cc, optimisation, "-pipe", "-fPIC", "-shared", "-I", tmp, str(Path(tmp) / f"{base}.c"),
                   *map(str, sources), "-o", str(library), "-lm"]  # fmt: skip
        # the compiler's own temporary files in this folder, not the user's TMPDIR: a run
        # interrupted while compiling leaves nothing there
        result = subprocess.run(command, capture_output=True, text=True, env={**os.environ, "TMPDIR": tmp})
        if result.returncode != 0:
            lines = result.stderr.strip().splitlines()
            first_error = next((line for line in lines if "error" in line), lines[-1] if lines else "?")
            warnings.warn(f"compiling {purpose} failed ({cc}: {first_error.strip()}); running uncompiled (slower)",
                          stacklevel=4)  # fmt: skip
            return None
        os.replace(library, target)  # atomic: concurrent workers see a whole file or none
    return target
