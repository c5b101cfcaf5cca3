"""Exact outlines of the lightening openings in a gear's web: round holes, arc (kidney) slots
and windows between spokes, as lines and circular arcs; their area, first and polar second
moments integrated on that outline; their radial extent and the ligaments they leave.

All lengths in m, angles in rad. An opening is described in its own frame (its centre line
along polar angle 0) and turned to its place by `place`; opening k sits at
``hole_phase + 2*pi*k/holes`` (`solver.geometry.hole_angles`), its centre on the circle of radius
``hole_circle_radius`` (Rc).

* ``round``: a circle of radius ``hole_radius`` centred at (Rc, 0).
* ``slot``: a kidney of radial width ``slot_width`` (w): the annular sector Rc -/+ w/2 over
  ``slot_angle`` (theta, the span between the centres of its two end arcs), closed by two
  semicircles of radius w/2. Area w*Rc*theta + pi*(w/2)^2; theta = 0 is a round hole of
  diameter w.
* ``window``: the part of the annulus Rc -/+ ``window_height``/2 between two spokes of width
  ``spoke_width`` (straight, of constant width, centred on the polar angles +-pi/holes), its four
  corners rounded with fillets of ``corner_radius`` tangent to the spoke side and to the arc.

Each outline is a closed, counter-clockwise chain of `Line` and `Arc` pieces (the opening's
inside on the left), which is what the FE mesher (`solver.fe.mesh`) draws and what the mass
properties (`solver.inertia`) integrate, by Green's theorem with Gauss-Legendre quadrature on each
piece (exact to rounding for the lines, to about 1e-15 for arcs of at most a quarter turn).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

OPENINGS = ("round", "slot", "window")


@dataclass(frozen=True)
class Line:
    """Straight piece from p0 to p1 [m]."""

    p0: tuple
    p1: tuple

    def at(self, s):
        """Points at the parameter(s) s in [0, 1] -> (x, y) [m], and their derivatives d/ds."""
        s = np.asarray(s, float)
        dx, dy = self.p1[0] - self.p0[0], self.p1[1] - self.p0[1]
        return self.p0[0] + s * dx, self.p0[1] + s * dy, np.full_like(s, dx), np.full_like(s, dy)

    @property
    def start(self):
        return self.p0

    @property
    def end(self):
        return self.p1


@dataclass(frozen=True)
class Arc:
    """Circular arc about ``centre`` [m] of ``radius`` [m] from polar angle a0 to a1 [rad] about
    the centre (a1 > a0: counter-clockwise, a1 < a0: clockwise)."""

    centre: tuple
    radius: float
    a0: float
    a1: float

    def at(self, s):
        s = np.asarray(s, float)
        a = self.a0 + s * (self.a1 - self.a0)
        da = self.a1 - self.a0
        c, sn = np.cos(a), np.sin(a)
        return (self.centre[0] + self.radius * c, self.centre[1] + self.radius * sn,
                -self.radius * sn * da, self.radius * c * da)

    def point(self, a: float):
        return (self.centre[0] + self.radius * math.cos(a), self.centre[1] + self.radius * math.sin(a))

    @property
    def start(self):
        return self.point(self.a0)

    @property
    def end(self):
        return self.point(self.a1)


@dataclass(frozen=True)
class OpeningShape:
    """What shapes one opening, SI: the fields of `solver.geometry.BodySpec` that matter for it."""

    kind: str                 # 'round', 'slot' or 'window'
    count: int                # openings on the circle [-]
    centre_radius: float      # Rc [m]
    hole_radius: float = 0.0  # round [m]
    slot_width: float = 0.0   # slot [m]
    slot_angle: float = 0.0   # slot [rad]
    spoke_width: float = 0.0  # window [m]
    corner_radius: float = 0.0  # window [m]
    window_height: float = 0.0  # window [m]


def shape_of(body) -> OpeningShape:
    """The `OpeningShape` of a `solver.geometry.BodySpec`."""
    return OpeningShape(body.opening, int(body.holes), body.hole_circle_radius, body.hole_radius, body.slot_width,
                        body.slot_angle, body.spoke_width, body.corner_radius, body.window_height)


# ---------------------------------------------------------------- outlines

def _ccw(a0: float, a1: float) -> float:
    """a1 moved by whole turns to lie in (a0, a0 + 2 pi]."""
    d = (a1 - a0) % (2 * math.pi)
    return a0 + (d if d > 0 else 2 * math.pi)


def window_corners(s: OpeningShape):
    """The upper half of a window in its own frame: (centre of the outer fillet, of the inner
    fillet) [m], the polar angles [rad] where the outer and the inner arc end (the window spans
    -gamma..gamma on each), and the normal n (into the window) and direction t (outwards) of the
    upper spoke side. Angles below zero mean the corners meet (no arc left)."""
    beta = math.pi / s.count
    n = np.array([math.sin(beta), -math.cos(beta)])
    t = np.array([math.cos(beta), math.sin(beta)])
    rho, half_w = s.corner_radius, 0.5 * s.spoke_width
    r_out = s.centre_radius + 0.5 * s.window_height
    r_in = s.centre_radius - 0.5 * s.window_height
    d = half_w + rho

    def centre(rc):        # fillet centre at distance rc from the gear centre, d from the side line
        along = math.sqrt(max(rc * rc - d * d, 0.0))
        return d * n + along * t
    c_out, c_in = centre(r_out - rho), centre(r_in + rho)
    g_out = math.atan2(c_out[1], c_out[0]) if r_out - rho > d else -math.inf
    g_in = math.atan2(c_in[1], c_in[0]) if r_in + rho > d else -math.inf
    return c_out, c_in, g_out, g_in, n, t


def local_outline(s: OpeningShape) -> list:
    """One opening in its own frame (centre line along +x), counter-clockwise: a list of `Line`
    and `Arc` pieces without zero-length ones [m, rad]."""
    rc = s.centre_radius
    if s.kind == "round":
        return [Arc((rc, 0.0), s.hole_radius, 0.0, 2 * math.pi)]
    if s.kind == "slot":
        h, r = 0.5 * s.slot_angle, 0.5 * s.slot_width
        e_up, e_lo = (rc * math.cos(h), rc * math.sin(h)), (rc * math.cos(h), -rc * math.sin(h))
        pieces = [Arc((0.0, 0.0), rc + r, -h, h), Arc(e_up, r, h, h + math.pi),
                  Arc((0.0, 0.0), rc - r, h, -h), Arc(e_lo, r, math.pi - h, 2 * math.pi - h)]
        return [p for p in pieces if p.a1 != p.a0]
    if s.kind == "window":
        c_out, c_in, g_out, g_in, n, _t = window_corners(s)
        rho = s.corner_radius
        r_out, r_in = rc + 0.5 * s.window_height, rc - 0.5 * s.window_height
        mirror = np.array([1.0, -1.0])
        up = []     # upper half, from the outer arc's end to the inner arc's start, counter-clockwise
        a_n = math.atan2(-n[1], -n[0])          # direction from a fillet centre to its tangent point on the side
        if rho > 0:
            a_o = math.atan2(c_out[1], c_out[0])
            up.append(Arc(tuple(c_out), rho, a_o, _ccw(a_o, a_n)))
            side_out, side_in = tuple(c_out - rho * n), tuple(c_in - rho * n)
            up.append(Line(side_out, side_in))
            a_i = math.atan2(-c_in[1], -c_in[0])
            up.append(Arc(tuple(c_in), rho, a_n, _ccw(a_n, a_i)))
        else:
            up.append(Line((r_out * math.cos(g_out), r_out * math.sin(g_out)), (r_in * math.cos(g_in), r_in * math.sin(g_in))))
        lo = []     # the mirror image of the upper half, traversed the other way
        for p in reversed(up):
            if isinstance(p, Line):
                lo.append(Line(tuple(np.array(p.p1) * mirror), tuple(np.array(p.p0) * mirror)))
            else:
                lo.append(Arc((p.centre[0], -p.centre[1]), p.radius, -p.a1, -p.a0))
        pieces = [Arc((0.0, 0.0), r_out, -g_out, g_out), *up, Arc((0.0, 0.0), r_in, g_in, -g_in), *lo]
        tiny = 1e-12 * rc      # corners of half the height meet: no straight side left between them
        return [p for p in pieces if not (p.a1 == p.a0 if isinstance(p, Arc)
                                          else math.hypot(p.p1[0] - p.p0[0], p.p1[1] - p.p0[1]) < tiny)]
    raise ValueError(f"unknown opening {s.kind!r}: one of {', '.join(OPENINGS)}")


def place(pieces: list, angle: float) -> list:
    """The pieces turned by ``angle`` [rad] about the gear centre."""
    c, sn = math.cos(angle), math.sin(angle)

    def rot(p):
        return (c * p[0] - sn * p[1], sn * p[0] + c * p[1])
    return [Line(rot(p.p0), rot(p.p1)) if isinstance(p, Line) else
            Arc(rot(p.centre), p.radius, p.a0 + angle, p.a1 + angle) for p in pieces]


def polygon(pieces: list, step: float) -> tuple[np.ndarray, np.ndarray]:
    """The closed outline sampled at about ``step`` [m] (at least 8 points an arc): (x, y) [m],
    the last point not repeated."""
    xs, ys = [], []
    for p in pieces:
        length = (abs(p.a1 - p.a0) * p.radius if isinstance(p, Arc)
                  else math.hypot(p.p1[0] - p.p0[0], p.p1[1] - p.p0[1]))
        k = max(int(math.ceil(length / step)), 8 if isinstance(p, Arc) else 1)
        x, y, _, _ = p.at(np.linspace(0.0, 1.0, k + 1)[:-1])
        xs.append(x)
        ys.append(y)
    return np.concatenate(xs), np.concatenate(ys)


# ---------------------------------------------------------------- mass properties

_GAUSS = np.polynomial.legendre.leggauss(16)
_ARC_SPLIT = math.pi / 4      # arcs are integrated in pieces of at most this angle [rad]


def outline_moments(pieces: list) -> tuple[float, float, float, float]:
    """Area [m²], first moments Sx = int x dA, Sy = int y dA [m³] and polar second moment about
    the origin J0 = int (x²+y²) dA [m⁴] of the region a closed counter-clockwise outline encloses
    (Green's theorem on each piece)."""
    xg, wg = _GAUSS
    s_nodes, s_weights = 0.5 * (xg + 1.0), 0.5 * wg
    area = sx = sy = j0 = 0.0
    for p in pieces:
        parts = [p]
        if isinstance(p, Arc):
            k = max(1, int(math.ceil(abs(p.a1 - p.a0) / _ARC_SPLIT)))
            a = np.linspace(p.a0, p.a1, k + 1)
            parts = [Arc(p.centre, p.radius, a[i], a[i + 1]) for i in range(k)]
        for q in parts:
            x, y, dx, dy = q.at(s_nodes)
            area += 0.5 * float(np.dot(s_weights, x * dy - y * dx))
            sx += 0.5 * float(np.dot(s_weights, x * x * dy))
            sy -= 0.5 * float(np.dot(s_weights, y * y * dx))
            j0 += float(np.dot(s_weights, x**3 * dy - y**3 * dx)) / 3.0
    return area, sx, sy, j0


def opening_area_moment(s: OpeningShape) -> tuple[float, float]:
    """(area [m²], polar second moment about the gear centre [m⁴]) of all openings together
    (each the same outline turned about the centre: the same area and moment)."""
    if s.count == 0:
        return 0.0, 0.0
    if s.kind == "window" and s.window_height == 0.0:
        return 0.0, 0.0          # a window of zero height takes nothing out
    area, _, _, j0 = outline_moments(local_outline(s))
    return s.count * area, s.count * j0


def slot_area(width: float, centre_radius: float, angle: float) -> float:
    """Closed form of one slot's area [m²]: the annular sector w*Rc*theta plus the two half
    discs pi*(w/2)^2."""
    return width * centre_radius * angle + math.pi * (0.5 * width) ** 2


# ---------------------------------------------------------------- extent and ligaments

def radial_extent(s: OpeningShape) -> tuple[float, float]:
    """(innermost, outermost) radius [m] an opening reaches."""
    rc = s.centre_radius
    half = {"round": s.hole_radius, "slot": 0.5 * s.slot_width, "window": 0.5 * s.window_height}[s.kind]
    return rc - half, rc + half


def angular_half_width(s: OpeningShape) -> float:
    """Half the polar angle [rad] an opening covers seen from the gear centre."""
    rc = s.centre_radius
    if s.kind == "round":
        return math.asin(min(1.0, s.hole_radius / rc))
    if s.kind == "slot":
        return 0.5 * s.slot_angle + math.asin(min(1.0, 0.5 * s.slot_width / rc))
    x, y = polygon(local_outline(s), 1e-3 * rc)
    return float(np.max(np.abs(np.arctan2(y, x))))


def between_openings(s: OpeningShape) -> float:
    """Narrowest web [m] between two neighbouring openings (between the ends of one slot for a
    single slot); +inf for a single round hole. Negative: they overlap."""
    n, rc = s.count, s.centre_radius
    if s.kind == "round":
        return 2 * rc * math.sin(math.pi / n) - 2 * s.hole_radius if n >= 2 else math.inf
    if s.kind == "slot":
        gap = 2 * math.pi / n - s.slot_angle          # between the end-arc centres of neighbours [rad]
        if gap >= math.pi:      # a single slot of less than half a turn: its ends face away from each other
            return math.inf
        return 2 * rc * math.sin(0.5 * gap) - s.slot_width
    return s.spoke_width
