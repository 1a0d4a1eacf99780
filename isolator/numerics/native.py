"""Compiling casadi functions to native code, cached on disk, called through ctypes.

casadi generates C for a function; it is compiled once with the system C
compiler into ``$ISOLATOR_CACHE`` (default ``~/.cache/isolator``; a folder of the user's own, made 0700,
refused if others may write into it) under a name derived from the source's hash, and loaded with ctypes
once its own hash is the one recorded when it was built; while it compiles, one line on stderr says so
(``ISOLATOR_QUIET=1`` silences it). Calls pass numpy
buffers without copies and release the GIL, so threads run in parallel. When no
compiler is available the casadi function itself is evaluated instead (slower,
same numbers).
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import shutil
import sys
import tempfile
import threading
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path

import casadi as ca
import numpy as np

from isolator.numerics.native_build import build_library, build_lock, cpu_identity, vector_lanes
from isolator.numerics.native_cache import cache_dir, private_cache, verified

__all__ = ["FLAGS", "PLAIN_FLAGS", "MappedFunction", "NativeFunction", "cache_dir", "compiled_library", "find_compiler",
           "vector_lanes"]

#: compiler flags of every compiled model: fast-math without the finite-math assumption (NaN and
#: infinity still propagate, so a diverging run is still detected); -march=native is safe because
#: the cache key includes the CPU's identity
#: how libraries are linked (part of the cache key): compiled with FLAGS, linked without -ffast-math
LINK = "link: -shared -fPIC -lm, no fast-math start-up"
FLAGS = ("-O3", "-march=native", "-ffast-math", "-fno-finite-math-only", "-fPIC", "-shared")
#: flags that compute as casadi's own evaluator does, operation by operation (no fast-math, no fused
#: multiply-adds, no CPU-specific code): the same numbers as the uncompiled function, bit for bit
PLAIN_FLAGS = ("-O2", "-ffp-contract=off", "-fPIC", "-shared")


_LOCK = threading.Lock()


def find_compiler(language: str = "c") -> str | None:
    """The C (``language="c"``) or C++ compiler to use: ``$CC``/``$CXX``, else the first of cc, gcc, clang
    (c++, g++, clang++) on the path; None when there is none.

    ``$CC``/``$CXX`` set to a command that is not found is not ignored without a word: a warning naming the
    variable, its value and the compiler used instead (once per process and value).
    """
    names = ("CC", "cc", "gcc", "clang") if language == "c" else ("CXX", "c++", "g++", "clang++")
    chosen = os.environ.get(names[0], "").strip()
    if chosen and shutil.which(chosen):
        return chosen
    found = next((name for name in names[1:] if shutil.which(name)), None)
    if chosen and (names[0], chosen) not in _WARNED:
        _WARNED.add((names[0], chosen))
        instead = f"compiling with {found} instead" if found else "and no other compiler is found"
        warnings.warn(f"{names[0]}: {chosen!r} is not found; {instead}", stacklevel=2)
    return found


#: the compiler variables already warned about, with their values
_WARNED: set[tuple[str, str]] = set()


def compiled_library(name: str, source: str, flags: Sequence[str] = FLAGS, language: str = "c") -> Path:
    """A shared library built from ``source``, cached in :func:`cache_dir` under a hash of the
    source, the flags, the compiler, casadi's version and the CPU.

    Parameters
    ----------
    name : str
        Prefix of the library's file name.
    source : str
        C or C++ source.
    flags : sequence of str
        Compiler flags (``-shared`` and ``-fPIC`` among them).
    language : {"c", "c++"}

    Returns
    -------
    Path
        The library.

    Raises
    ------
    RuntimeError
        No compiler for the language, or it failed (its first error line is in the message).
    ParameterError
        A cache folder others may write into (:func:`private_cache`).

    Notes
    -----
    The cache folder is made private (0700) and refused if others may write into it; each library's
    SHA-256 is recorded beside it when it is built, and a library whose hash is not the one recorded (one
    planted in the folder, or damaged) is built again rather than loaded.
    """
    compiler = find_compiler(language)
    if compiler is None:
        raise RuntimeError(f"no {language.upper()} compiler found (set {'CC' if language == 'c' else 'CXX'})")
    digest = hashlib.sha256(
        (source + " ".join(flags) + ca.CasadiMeta.version() + compiler + cpu_identity() + LINK).encode()
    ).hexdigest()[:20]
    folder = private_cache()
    target = folder / f"{name}-{digest}.so"
    with _LOCK, build_lock(folder / f"{name}-{digest}.lock"):
        if not verified(target):  # missing, or not the library built here (planted, damaged): built again
            _announce(language)
            build_library(compiler, name, source, flags, language, target)
    return target


_ANNOUNCED: set[str] = set()


def _announce(language: str) -> None:
    """Say on stderr that compiling is under way (it takes seconds): once per process and language, and
    not with ``ISOLATOR_QUIET=1``."""
    if language in _ANNOUNCED or os.environ.get("ISOLATOR_QUIET", "") not in ("", "0"):
        return
    _ANNOUNCED.add(language)
    what = "the model for this structure" if language == "c" else "the integrator"
    print(f"isolator: compiling {what} (first use, a few seconds)...", file=sys.stderr, flush=True)


class NativeFunction:
    """A casadi function evaluated from compiled C when possible.

    Parameters
    ----------
    function : casadi.Function
        Dense inputs and outputs.
    compile : bool
        Try to compile (True) or always use casadi's evaluator (False).
    companions : tuple of casadi.Function
        More functions compiled into the same library (e.g. the function's
        ``reverse(1)``, which :meth:`external` then uses for derivatives).
    optimisation : str
        The compiler's optimisation flag (big derivative code compiles much
        faster at ``-O1``).
    flags : sequence of str, optional
        All the compiler's flags instead (:data:`PLAIN_FLAGS`: the evaluator's numbers exactly).
    """

    def __init__(
        self,
        function: ca.Function,
        compile: bool = True,
        companions: tuple[ca.Function, ...] = (),
        optimisation: str = "-O3",
        flags: Sequence[str] | None = None,
    ) -> None:
        self.function = function
        self.companions = companions
        self.flags = [optimisation, *FLAGS[1:]] if flags is None else list(flags)
        self.name = function.name()
        self.in_shapes = [function.size_in(i) for i in range(function.n_in())]
        self.out_shapes = [function.size_out(i) for i in range(function.n_out())]
        self.library: Path | None = None
        self._lib: ctypes.CDLL | None = None
        self._local = threading.local()
        if compile:
            try:
                self.library = self._build()
            except (OSError, RuntimeError) as exc:
                warnings.warn(
                    f"could not compile the model ({exc}); using casadi's evaluator (slower)",
                    RuntimeWarning,
                    stacklevel=2,
                )
        if self.library is not None:
            self._load(self.library)

    @property
    def native(self) -> bool:
        """True when calls run compiled code."""
        return self._lib is not None

    def _build(self) -> Path:
        with tempfile.TemporaryDirectory() as tmp:
            generator = ca.CodeGenerator(f"{self.name}.c", {"with_header": False})
            generator.add(self.function)
            for extra in self.companions:
                generator.add(extra)
            generator.generate(tmp + os.sep)
            source = Path(tmp, f"{self.name}.c").read_text()
        return compiled_library(self.name, source, self.flags)

    def _load(self, path: Path) -> None:
        lib = ctypes.CDLL(str(path))
        fn = getattr(lib, self.name)
        fn.restype = ctypes.c_int
        fn.argtypes = [ctypes.c_void_p] * 4 + [ctypes.c_int]
        work = getattr(lib, f"{self.name}_work")
        sizes = [ctypes.c_longlong() for _ in range(4)]
        work(*[ctypes.byref(s) for s in sizes])
        self._sz = [s.value for s in sizes]
        self._fn = fn
        self._lib = lib

    def __call__(self, *inputs: np.ndarray) -> list[np.ndarray]:
        """Evaluate; inputs and outputs are arrays in casadi's column-major layout.

        Each input is given as an array whose memory (C order) is the
        column-major content of the casadi input; outputs are returned as
        float arrays of shape ``(columns, rows)``.
        """
        if self._lib is None:
            value = self.function(*[self._as_dm(x, shape) for x, shape in zip(inputs, self.in_shapes, strict=False)])
            values = value if isinstance(value, tuple | list) else [value]
            return [np.asarray(o, dtype=float).T.copy() for o in values]
        ins = [np.ascontiguousarray(x, dtype=np.float64) for x in inputs]
        for x, (r, c) in zip(ins, self.in_shapes, strict=False):
            if x.size != r * c:
                raise ValueError(f"{self.name}: input of {x.size} values, expected {r}x{c}")
        outs = [np.empty((c, r)) for (r, c) in self.out_shapes]
        pointers, _keep = self._pointers(ins, outs)
        status = self._fn(*pointers)
        if status != 0:
            raise RuntimeError(f"{self.name}: native evaluation failed ({status})")
        return outs

    def _work(self) -> tuple[np.ndarray, np.ndarray]:
        """This thread's work arrays (reused: big fresh ones cost page faults on every call)."""
        work = getattr(self._local, "work", None)
        if work is None:
            _, _, sz_iw, sz_w = self._sz
            work = (np.empty(max(sz_iw, 1), dtype=np.int64), np.empty(max(sz_w, 1), dtype=np.float64))
            self._local.work = work
        return work

    def external(self) -> ca.Function:
        """The compiled function as a casadi function, for symbolic graphs (derivatives from
        companions such as ``adj1_<name>``); the original function when nothing was compiled."""
        if self.library is None:
            return self.function
        return ca.external(self.name, str(self.library))

    def bound(self) -> Callable[..., list[np.ndarray]]:
        """A caller for many small calls from one thread, with its buffers allocated once.

        Same arguments as calling the object; the returned output arrays are
        reused (overwritten) by the next call, so copy what you keep.
        """
        if self._lib is None:
            return self.__call__
        ins = [np.empty(r * c) for (r, c) in self.in_shapes]
        outs = [np.empty((c, r)) for (r, c) in self.out_shapes]
        pointers, keep = self._pointers(ins, outs, own=True)
        fn = self._fn

        def call(*inputs: np.ndarray) -> list[np.ndarray]:
            for buffer, x in zip(ins, inputs, strict=True):
                buffer[:] = np.ravel(x)
            if fn(*pointers) != 0:
                raise RuntimeError(f"{self.name}: native evaluation failed")
            return outs

        call.__dict__["buffers"] = keep  # what the pointers point into: alive as long as the caller
        return call

    def _pointers(self, ins: list[np.ndarray], outs: list[np.ndarray], own: bool = False) -> tuple[tuple, tuple]:
        """The compiled function's five arguments for these buffers, and the objects they point into
        (keep those alive while the pointers are used): this thread's argument arrays filled anew, or with
        ``own`` arrays of their own (for a caller that keeps them)."""
        slots = None if own else getattr(self._local, "slots", None)
        if slots is None:
            sz_arg, sz_res, _, _ = self._sz
            arg = (ctypes.c_void_p * max(sz_arg, len(self.in_shapes)))()
            res = (ctypes.c_void_p * max(sz_res, len(self.out_shapes)))()
            iw, w = self._work()
            slots = (arg, res, (ctypes.addressof(arg), ctypes.addressof(res), iw.ctypes.data, w.ctypes.data, 0),
                     (iw, w))
            if not own:
                self._local.slots = slots
        arg, res, pointers, work = slots
        for k in range(len(self.in_shapes)):  # an input not given is null (zeros), as casadi reads it
            arg[k] = ins[k].ctypes.data if k < len(ins) else None
        for k in range(len(self.out_shapes)):
            res[k] = outs[k].ctypes.data if k < len(outs) else None
        return pointers, (arg, res, work, ins, outs)

    @staticmethod
    def _as_dm(x: np.ndarray, shape: tuple[int, int]) -> ca.DM:
        r, c = shape
        return ca.DM(np.asarray(x, dtype=float).reshape(c, r).T)


class MappedFunction:
    """A casadi function evaluated column by column for many argument sets, compiled in blocks.

    Two compiled forms, each built on first use: one argument set per call
    (for a few sets) and ``block`` sets per call (for many).

    Parameters
    ----------
    function : casadi.Function
        Of column-vector inputs and outputs (outputs may be matrices).
    name : str
        Name of the compiled block function.
    block : int
        Argument sets per compiled call of the block form (its last call is padded).
    optimisation : str
        Compiler optimisation flag.
    flags : sequence of str, optional
        All the compiler's flags instead (as :class:`NativeFunction` takes them).
    """

    def __init__(self, function: ca.Function, name: str, block: int = 32, optimisation: str = "-O3",
                 flags: Sequence[str] | None = None) -> None:
        self.function = function
        self.name = name
        self.block = block
        self.optimisation = optimisation
        self.flags = flags
        self.out_shapes = [function.size_out(i) for i in range(function.n_out())]
        self._native: dict[int, NativeFunction] = {}
        self._lock = threading.Lock()
        self._local = threading.local()

    def _compiled(self, block: int) -> NativeFunction:
        with self._lock:
            if block not in self._native:
                mapped = self.function.map(block) if block > 1 else self.function
                args = mapped.mx_in()
                self._native[block] = NativeFunction(
                    ca.Function(f"{self.name}_b{block}", args, [ca.densify(o) for o in mapped.call(args)]),
                    optimisation=self.optimisation, flags=self.flags,
                )
            return self._native[block]

    def _one_by_one(self, native: NativeFunction) -> Callable[..., list[np.ndarray]]:
        """This thread's caller of the one-set form (:meth:`NativeFunction.bound`), made once."""
        call = getattr(self._local, "call", None)
        if call is None:
            call = self._local.call = native.bound()
        return call

    def __call__(self, *inputs: np.ndarray) -> list[np.ndarray]:
        """Evaluate for ``N`` argument sets.

        Parameters
        ----------
        *inputs : ndarray
            Each (N, size), or (size,) for a value shared by all sets.

        Returns
        -------
        list of ndarray
            One per output, (N, rows) for column outputs and (N, rows, columns) otherwise.
        """
        n = max((x.shape[0] for x in inputs if np.ndim(x) == 2), default=1)
        b = 1 if n <= 4 else self.block
        native = self._compiled(b)
        outs = [np.empty((n, r, c)) for r, c in self.out_shapes]
        if b == 1 and native.native:  # a few sets: one call each through this thread's buffers
            call = self._one_by_one(native)
            rows = [np.asarray(x, dtype=float) for x in inputs]
            for i in range(n):
                values = call(*[x if x.ndim == 1 else x[i] for x in rows])
                for out, value, (r, c) in zip(outs, values, self.out_shapes, strict=True):
                    out[i] = value.reshape(c, r).T
            return [o[:, :, 0] if c == 1 else o for o, (r, c) in zip(outs, self.out_shapes, strict=True)]
        for lo in range(0, n, b):
            hi = min(lo + b, n)
            args = []
            for x in inputs:
                x = np.asarray(x, dtype=float)
                if x.ndim == 1:
                    args.append(np.broadcast_to(x, (b, x.size)) if b > 1 else x)
                    continue
                part = x[lo:hi]
                if hi - lo < b:
                    part = np.concatenate([part, np.repeat(part[-1:], b - (hi - lo), axis=0)])
                args.append(part)
            for out, value, (r, c) in zip(outs, native(*args), self.out_shapes, strict=True):
                # casadi's column-major (r, c) blocks side by side: value is (b c, r)
                out[lo:hi] = value.reshape(b, c, r)[: hi - lo].transpose(0, 2, 1)
        return [o[:, :, 0] if c == 1 else o for o, (r, c) in zip(outs, self.out_shapes, strict=True)]
