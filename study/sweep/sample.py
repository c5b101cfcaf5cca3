"""Sampled studies: scene fields drawn from distributions (Monte Carlo over manufacturing
deviations), reproducible from a seed.

The ``[sample]`` table of a study file (or ``make_study(..., sample=...)``)::

    [sample]
    size = 256
    method = "sobol"           # "random", "lhs" or "sobol" (scipy.stats.qmc); default "random"
    seed = 1                   # the same seed, the same draws
    design = "saltelli"        # optional: the Saltelli design for Sobol indices (below)
    "gear1.errors.seed" = {integers = [0, 1000000]}           # both ends included
    "gear1.errors.eccentricity" = {uniform = [0.0, 6.0]}      # um
    "gear1.modification.tip_relief" = {normal = [2.0, 0.5], bounds = [1.0, 3.0]}   # mean, sd; um

Any numeric scene field can be drawn: ``uniform = [lo, hi]`` and ``normal = [mean, sd]`` for a
real field, ``integers = [lo, hi]`` for an integer one (or a real one). A normal is truncated to
its ``bounds`` and to the field's own range (``tip_relief >= 0``, say). A zero-width
distribution (lo = hi, sd = 0) holds the field at that value in every build: one tolerance
switched off inside a sample. A distribution that cannot be drawn (lo > hi, sd < 0, a field that is not a number, a range outside the field's)
is a `SceneError` naming the field, raised before any work.

Draws: ``size`` points of the unit hypercube (one column per drawn field) by the method, each
column mapped through its distribution's inverse CDF. With ``design = "saltelli"`` the study
runs the design of Saltelli et al. (2010) for first-order and total Sobol indices: two
independent matrices A and B of ``size`` rows (the two halves of one 2d-column draw), and for
each drawn field i the matrix AB_i (A with column i taken from B): ``size x (d + 2)`` builds,
archived in the order A, B, AB_1 ... AB_d (``sample_block``: 0, 1, 2 ... d + 1) with the row of
each (``sample_row``). Every build is an ordinary study point; with a ``[grid]``, every grid
point gets the whole sample (the same draws).
"""
from __future__ import annotations

import copy
import dataclasses
import functools
import math
import warnings
from dataclasses import dataclass

import numpy as np

from study.scene import INT_MAX, SceneError, get_dotted, scene_field, scene_fields_from_dict, set_dotted

METHODS = ("random", "lhs", "sobol")
DESIGNS = ("plain", "saltelli")
SAMPLE_KEYS = ("size", "method", "seed", "design")
KINDS = ("uniform", "normal", "integers")


@dataclass(frozen=True)
class Distribution:
    """How one scene field is drawn. ``params``: uniform (lo, hi), normal (mean, sd), integers
    (lo, hi) with both ends included; ``bounds``: the interval the draws are held to (a normal's
    truncation, the field's range included; +-inf where open). Values in the scene's units."""
    path: str
    kind: str
    params: tuple[float, float]
    bounds: tuple[float, float]
    integer: bool              # the field is an integer one: draws are ints

    def ppf(self, u: np.ndarray) -> np.ndarray:
        """Inverse CDF: draws from points ``u`` of (0, 1)."""
        u = np.asarray(u, dtype=float)
        a, b = self.params
        if self.kind == "uniform":
            return a + u * (b - a)
        if self.kind == "integers":
            x = np.minimum(np.floor(a + u * (b - a + 1.0)), b)
            return x.astype(np.int64) if self.integer else x
        if b == 0.0:         # no spread: the mean in every build
            return np.full(u.shape, float(a))
        from scipy.stats import truncnorm
        lo, hi = self.bounds
        return truncnorm.ppf(u, (lo - a) / b, (hi - a) / b, loc=a, scale=b)

    def describe(self) -> str:
        """The distribution in words, e.g. 'normal(2, 0.5) within [1, 3]'."""
        a, b = self.params
        if self.fixed:
            return f"{self.kind} [{a:g}, {b:g}]: fixed at {a:g}"
        if self.kind == "normal":
            lo, hi = self.bounds
            return f"normal(mean {a:g}, sd {b:g}) within [{lo:g}, {hi:g}]"
        return f"{self.kind} [{a:g}, {b:g}]" + (" (ends included)" if self.kind == "integers" else "")

    @property
    def fixed(self) -> bool:
        """A zero-width distribution (lo = hi, sd = 0): the same value in every build."""
        return self.params[1] == 0.0 if self.kind == "normal" else self.params[0] == self.params[1]

    def spec(self) -> dict:
        """The TOML table this distribution was given as (bounds only where given)."""
        out = {self.kind: list(self.params)}
        if self.kind == "normal" and self.given_bounds is not None:
            out["bounds"] = list(self.given_bounds)
        return out

    given_bounds: tuple[float, float] | None = None


@dataclass(frozen=True)
class Sample:
    """The [sample] table of a study, checked: how many builds, how they are drawn, and from what."""
    size: int
    method: str
    seed: int
    design: str
    fields: tuple[Distribution, ...]

    @property
    def paths(self) -> tuple[str, ...]:
        return tuple(f.path for f in self.fields)

    @property
    def builds(self) -> int:
        """Number of points of the sample: ``size``, or ``size x (d + 2)`` for the Saltelli design."""
        return self.size * (len(self.fields) + 2) if self.design == "saltelli" else self.size

    @functools.cached_property
    def unit(self) -> np.ndarray:
        """The draws in the unit hypercube, (builds, d), in archive order."""
        d = len(self.fields)
        cols = 2 * d if self.design == "saltelli" else d
        u = unit_points(self.method, self.size, cols, self.seed)
        if self.design == "plain":
            return u
        a, b = u[:, :d], u[:, d:]
        mixed = []
        for i in range(d):
            ab = a.copy()
            ab[:, i] = b[:, i]
            mixed.append(ab)
        return np.concatenate([a, b, *mixed])

    @functools.cached_property
    def values(self) -> dict[str, np.ndarray]:
        """{dotted field: its drawn values over the builds} in the scene's units."""
        return {f.path: f.ppf(self.unit[:, i]) for i, f in enumerate(self.fields)}

    @property
    def block(self) -> np.ndarray:
        """Which matrix each build belongs to: 0 (A, or every build of a plain design), 1 (B),
        2 + i (AB_i, field i from B)."""
        return np.repeat(np.arange(self.builds // self.size, dtype=np.int8), self.size)

    @property
    def row(self) -> np.ndarray:
        """Row of each build within its matrix (builds with the same row share their A and B draws)."""
        return np.tile(np.arange(self.size, dtype=np.int64), self.builds // self.size)

    def point_values(self, i: int) -> dict:
        """{dotted field: value} of build ``i`` as Python numbers."""
        return {p: v[i].item() for p, v in self.values.items()}

    def table(self) -> dict:
        """The [sample] table that gives this sample (for the archived study text)."""
        out = {"size": self.size, "method": self.method, "seed": self.seed}
        if self.design != "plain":
            out["design"] = self.design
        out.update({f.path: f.spec() for f in self.fields})
        return out

    def describe(self) -> str:
        """One line: method, size, seed, design and builds."""
        design = f", Saltelli design ({self.builds} builds)" if self.design == "saltelli" else ""
        return f"{self.method}, {self.size} draws, seed {self.seed}{design}"


def unit_points(method: str, n: int, d: int, seed: int) -> np.ndarray:
    """``n`` points of the unit hypercube [0, 1)^d by ``method`` ('random', 'lhs', 'sobol':
    scrambled), reproducible from ``seed``."""
    from scipy.stats import qmc
    rng = np.random.default_rng(seed)
    if method == "random":
        return rng.random((n, d))
    if method == "lhs":
        return qmc.LatinHypercube(d, rng=rng).random(n)
    with warnings.catch_warnings():      # balance needs n = 2^k; other sizes are still a valid draw
        warnings.filterwarnings("ignore", message=".*balance properties of Sobol.*")
        return qmc.Sobol(d, scramble=True, rng=rng).random(n)


# ---------------------------------------------------------------- reading and checking

def _scene_table(path: str) -> bool:
    """True when ``path`` names a table of the scene (``gear1.errors``), not a value field."""
    try:
        f = scene_field(path)
    except SceneError:
        return False
    return dataclasses.is_dataclass(f.default_factory) if f.default_factory is not dataclasses.MISSING else False


def flatten_sample(table: dict, prefix: str = "") -> dict:
    """{dotted key: value} of a [sample] table: nested scene tables (unquoted dotted keys) are
    followed down to their fields, whose value is the distribution table."""
    out = {}
    for k, v in table.items():
        path = f"{prefix}.{k}" if prefix else k
        if isinstance(v, dict) and _scene_table(path):
            out.update(flatten_sample(v, path))
        else:
            out[path] = v
    return out


def _number(v) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)


def _pair(path: str, kind: str, v, what: str) -> tuple[float, float]:
    if not (isinstance(v, list) and len(v) == 2 and all(_number(x) for x in v)):
        raise SceneError(path, f"[sample] {kind} takes [{what}], two finite numbers, got {v!r}")
    return v[0], v[1]


def _check_in_field(base: dict, path: str, value, what: str) -> None:
    """SceneError naming the field when ``value`` is outside the field's own range (or type)."""
    data = copy.deepcopy(base)
    set_dotted(data, path, value)
    try:
        scene_fields_from_dict(data)
    except SceneError as e:
        if e.field == path:
            raise SceneError(path, f"[sample] {what} {value!r} is outside the field's range: {e.reason}") from None
        raise


def _field_range(path: str) -> tuple[float, float]:
    md = scene_field(path).metadata
    lo, hi = md.get("lo"), md.get("hi")
    return (-math.inf if lo is None else float(lo)), (math.inf if hi is None else float(hi))


def distribution(base: dict, path: str, spec) -> Distribution:
    """One drawn field checked against the base scene (data of a study's scene tables)."""
    node = get_dotted(scene_fields_from_dict(base), path)     # SceneError for an unknown path
    if dataclasses.is_dataclass(node):
        raise SceneError(path, "is a table of the scene, not a value")
    if isinstance(node, bool) or not isinstance(node, int | float):
        raise SceneError(path, f"[sample] draws numbers, this field is {type(node).__name__} ({node!r})")
    integer = isinstance(node, int)
    if not isinstance(spec, dict):
        raise SceneError(path, f"[sample] takes a distribution table ({{uniform = [lo, hi]}}, "
                               f"{{normal = [mean, sd]}} or {{integers = [lo, hi]}}), got {spec!r}")
    kinds = [k for k in spec if k in KINDS]
    extra = [k for k in spec if k not in (*KINDS, "bounds")]
    if len(kinds) != 1 or extra:
        raise SceneError(path, f"[sample] a distribution is one of {', '.join(KINDS)} (normal with optional "
                               f"bounds), got keys {sorted(spec)}")
    kind = kinds[0]
    if "bounds" in spec and kind != "normal":
        raise SceneError(path, f"[sample] bounds go with a normal distribution, not {kind}")
    if integer and kind != "integers":
        raise SceneError(path, f"[sample] an integer field takes {{integers = [lo, hi]}}, not {kind}")
    field_lo, field_hi = _field_range(path)
    if kind in ("uniform", "integers"):
        lo, hi = _pair(path, kind, spec[kind], "lo, hi")
        if kind == "integers" and not (float(lo).is_integer() and float(hi).is_integer()):
            raise SceneError(path, f"[sample] integers takes two integers, got {spec[kind]!r}")
        if not lo <= hi:     # lo = hi: the field held at that value (a tolerance switched off)
            raise SceneError(path, f"[sample] {kind} [lo, hi] needs lo <= hi (lo = hi: a fixed value), got [{lo}, {hi}]")
        for v, what in ((lo, "lower end"), (hi, "upper end")):
            _check_in_field(base, path, int(v) if integer else float(v), f"{kind} {what}")
        if kind == "integers":
            lo, hi = int(lo), int(hi)
        return Distribution(path, kind, (lo, hi), (lo, hi), integer)
    mean, sd = _pair(path, kind, spec[kind], "mean, sd")
    if not sd >= 0:      # sd = 0: the field held at its mean (a tolerance switched off)
        raise SceneError(path, f"[sample] normal [mean, sd] needs sd >= 0 (0: a fixed value), got sd = {sd}")
    given = None
    lo, hi = field_lo, field_hi
    if "bounds" in spec:
        given = _pair(path, "bounds", spec["bounds"], "lo, hi")
        if not given[0] < given[1]:
            raise SceneError(path, f"[sample] normal bounds [lo, hi] need lo < hi, got {list(given)}")
        for v, what in ((given[0], "lower bound"), (given[1], "upper bound")):
            _check_in_field(base, path, float(v), f"normal {what}")
        lo, hi = max(lo, given[0]), min(hi, given[1])
    if not lo <= mean <= hi:
        raise SceneError(path, f"[sample] normal mean {mean} lies outside the range it is held to [{lo:g}, {hi:g}] "
                               "(the field's and the bounds')")
    return Distribution(path, kind, (float(mean), float(sd)), (lo, hi), False, given)


def parse_sample(table, base: dict, taken: tuple[str, ...] = ()) -> Sample:
    """The [sample] table checked against the base scene (``taken``: fields swept by the grid,
    which cannot also be drawn). SceneError naming the key or field."""
    if not isinstance(table, dict):
        raise SceneError("sample", f"must be a table, got {table!r}")
    flat = flatten_sample(table)
    size = flat.pop("size", None)
    if isinstance(size, bool) or not isinstance(size, int) or size < 2:
        raise SceneError("sample.size", f"must be an integer of at least 2 (the number of draws), got {size!r}")
    method = flat.pop("method", "random")
    if method not in METHODS:
        raise SceneError("sample.method", f"must be one of {', '.join(map(repr, METHODS))}, got {method!r}")
    seed = flat.pop("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise SceneError("sample.seed", f"must be a non-negative integer, got {seed!r}")
    if seed > INT_MAX:      # (its archive could not store it: refused before any build)
        raise SceneError("sample.seed", f"must fit in 64 bits (the archive's integers): at most {INT_MAX}, got {seed}")
    design = flat.pop("design", "plain")
    if design not in DESIGNS:
        raise SceneError("sample.design", f"must be one of {', '.join(map(repr, DESIGNS))}, got {design!r}")
    fields = []
    for path, spec in flat.items():
        if path in taken:
            raise SceneError(path, "is swept by [grid] and drawn by [sample]: give it in one of them")
        fields.append(distribution(base, path, spec))
    if not fields:
        raise SceneError("sample", "draws no field: give at least one \"dotted.field\" = {distribution}")
    return Sample(size, method, seed, design, tuple(fields))
