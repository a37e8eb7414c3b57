"""pdsm for tools: read penumbra deep shadow maps and bake them from Python.

    import numpy as np, pdsm
    f = pdsm.open("plates.exr")
    f.header["resolution"]                     # as `pdsm info --json` words it
    a = f.attenuation(np.array([[0.0, 0.0, 0.0]]))  # fraction of the light hidden, per point

Reading uses the code `pdsm query` uses (tiles read on demand through a bounded cache, the same
bilinear blend): a point's answer is the double `pdsm query` prints. `attenuation` releases the
GIL, so threads sharing one File query in parallel.

`bake` runs the `pdsm` command line built beside this module (a bake is a process of its own:
its GL contexts, threads and memory stay out of the interpreter) and opens what it wrote.
"""

import json
import os
import subprocess

from . import _pdsm
from ._build_paths import PDSM_CLI as _BUILT_CLI

__version__ = _pdsm.__version__
Error = _pdsm.Error
DEFAULT_CACHE_MIB = _pdsm.DEFAULT_CACHE_MIB

__all__ = ["open", "bake", "File", "Error", "BakeError", "DEFAULT_CACHE_MIB"]


class BakeError(Error):
    """A bake that failed: the message is the command line's own error."""


class File:
    """A PDSM file opened for queries (a context manager; nothing to close but the file).

    path     the file's path
    lights   its lights' names in file order ("" for a one-light file whose light has no name)
    header   a dict, as `pdsm info --json` prints it without the vertex counts: the light's
             header for a one-light file, {"lights": [header, ...]} for several
    headers  one header dict per light, in file order
    """

    def __init__(self, path, cache_mib=DEFAULT_CACHE_MIB):
        self._file = _pdsm.File(os.fspath(path), int(cache_mib))
        self.headers = [json.loads(text) for text in self._file.header_json()]

    @property
    def path(self):
        return self._file.path

    @property
    def lights(self):
        return self._file.light_names

    @property
    def header(self):
        return self.headers[0] if len(self.headers) == 1 else {"lights": self.headers}

    def attenuation(self, points, light=None):
        """The fraction of the light hidden at each world point (nan outside the map).

        points  array-like of shape (n, 3), world x, y, z (converted to float64)
        light   None: every light; a light's name; or its index in `lights`
        returns an ndarray of shape (n,) for one light (or a one-light file), (n, lights) with
                one column per light in file order for None on a file of several
        """
        return self._file.attenuation(points, light)

    @property
    def tiles_read(self):
        """Tiles read from the file so far (re-reads of tiles the cache let go included)."""
        return self._file.tiles_read

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self._file = None
        return False

    def __repr__(self):
        return f"pdsm.File({self.path!r}, lights={self.lights!r})"


def open(path, cache_mib=DEFAULT_CACHE_MIB):  # noqa: A001 (as builtins.open and gzip.open)
    """Opens a PDSM file; tiles are read as queries need them, `cache_mib` MiB kept at most.

    Raises FileNotFoundError for no file, pdsm.Error for one that is not a readable PDSM.
    """
    return File(path, cache_mib)


# bake()'s keywords: the command line's flags, '_' for '-'. A value of True gives a flag alone.
_BAKE_FLAGS = {
    "resolution", "samples", "sm_resolution", "epsilon", "tile_size", "depth_bias", "sampling",
    "adaptive_tolerance", "adaptive_min_samples", "surfaces_only", "threads",
    "samples_per_task", "event_memory_mib", "target_error", "preview", "weighting",
    "max_refinement",
}


def _cli():
    return os.environ.get("PDSM_CLI", _BUILT_CLI)


def bake(scene, output, **overrides):
    """Bakes `scene` (a scene JSON path) into `output` (.exr) and returns it opened.

    Keywords override the scene's bake fields as `pdsm bake`'s flags do: resolution (an int for
    a square map, a (width, height) pair, or "WxH"), samples, sm_resolution, epsilon, tile_size,
    depth_bias, sampling ("sobol", "blue-noise", ...), adaptive_tolerance, adaptive_min_samples,
    surfaces_only=True, weighting ("unweighted" or "emitter"), max_refinement (1, 2, 4 or 8); and
    threads, samples_per_task, event_memory_mib, target_error. No
    picture is written unless preview="path.png". The same scene and keywords give the same
    file bytes as `pdsm bake`. Raises TypeError for an unknown keyword and pdsm.BakeError
    with the command line's message when the bake fails (nothing is left at `output` then).
    """
    unknown = sorted(set(overrides) - _BAKE_FLAGS)
    if unknown:
        raise TypeError(f"bake(): unknown keyword {unknown[0]!r}; known: "
                        + ", ".join(sorted(_BAKE_FLAGS)))
    args = [_cli(), "bake", os.fspath(scene), "-o", os.fspath(output)]
    if "preview" not in overrides:
        args.append("--no-preview")
    for key, value in overrides.items():
        flag = "--" + key.replace("_", "-")
        if key == "resolution":
            if isinstance(value, int):
                value = f"{value}x{value}"
            elif not isinstance(value, str):
                width, height = value
                value = f"{int(width)}x{int(height)}"
        if value is True:
            args.append(flag)
        elif value is False or value is None:
            continue
        else:
            args += [flag, str(os.fspath(value) if key == "preview" else value)]
    run = subprocess.run(args, capture_output=True, text=True)
    if run.returncode != 0:
        lines = [line for line in run.stderr.splitlines() if line.strip()]
        raise BakeError(lines[-1] if lines else f"{args[0]} exited with {run.returncode}")
    return File(output)
