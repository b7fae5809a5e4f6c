"""The compiled kernels (numba) of the norms: whole rules over triangles in one pass, where numpy
forms arrays of every point, part and power.

- ``p1_rule_largest`` and ``p1_rule_sum``: a norm under the paper's conventions of a P1 function ``v`` as the error
  ``e = −v`` against ``u ≡ 0`` (an algebraic error ``δ``, ``studies.scene.norm.algebraic_uncertainties``),
  at the points of the conventions' triangle rule (``fem.norms.conventional``).
- ``manufactured_rule_integrals`` and ``manufactured_survey``: the true norms' conical rule over a
  triangle and their survey of the triangles (``fem.norms.true``) for the manufactured problem,
  whose ``u`` and ``∇u`` come from ``fem.point_kernels.manufactured_point``.

Each kernel performs the numpy code's operations per point in their order (no ``fastmath``: no
contracted multiply–adds); the survey is the numpy survey bit for bit, while the sums over a
triangle's points and over the triangles run in order where numpy's products and pairwise sums
take their own, so those values agree with numpy's to round-off
(``docs/evidence/design-measurements.md#compiled-norm-kernels``).  The evaluators call them only
where the compiled point kernels are enabled (``fem.problem.compiled_points``: large meshes), so
numba's import is paid there only.
"""

from __future__ import annotations

import math

import numba

from signorini.fem.point_kernels import manufactured_point

# The codes of the parts of a norm (``fem.norms.families.PARTS``, in that order).
PART_E, PART_E_PLUS, PART_E_MINUS, PART_D1, PART_D2, PART_GRAD = range(6)


@numba.njit(cache=True, inline="always")
def _rolled(px, py, t, el, role):  # pragma: no cover - compiled
    """The vertices of triangle ``el`` in ``fem.norms.conventional._rolled_t``'s order for the
    Stroud rule's ``role`` (as stored for ``role < 0``)."""
    a, b, c = t[0, el], t[1, el], t[2, el]
    if role < 0:
        return a, b, c
    e01x, e01y = px[b] - px[a], py[b] - py[a]
    e02x, e02y = px[c] - px[a], py[c] - py[a]
    e12x, e12y = px[c] - px[b], py[c] - py[b]
    dots = (abs(e01x * e02x + e01y * e02y), abs(e12x * e01x + e12y * e01y), abs(e02x * e12x + e02y * e12y))
    right = 0
    if dots[1] < dots[right]:
        right = 1
    if dots[2] < dots[right]:
        right = 2
    if not e01x * e02y - e01y * e02x > 0:  # clockwise: (a, c, b), the right angle's index mapped alike
        b, c = c, b
        right = (0, 2, 1)[right]
    order = (a, b, c)
    start = (right + role) % 3
    return order[start], order[(start + 1) % 3], order[(start + 2) % 3]


@numba.njit(cache=True, inline="always")
def _magnitude(code, e, g0, g1):  # pragma: no cover - compiled
    """``|part|`` of ``fem.norms.families.magnitude`` from ``e`` and ``∇e = (g0, g1)``."""
    if code == PART_E:
        return abs(e)
    if code == PART_E_PLUS:
        return max(e, 0.0)
    if code == PART_E_MINUS:
        return max(-e, 0.0)
    if code == PART_D1:
        return abs(g0)
    if code == PART_D2:
        return abs(g1)
    return math.hypot(g0, g1)


@numba.njit(cache=True, inline="always")
def _squared(code, e, g0, g1):  # pragma: no cover - compiled
    """The squared magnitude of a part, as ``fem.norms.true._squared`` forms it: ``x · x`` of the
    part's value, ``g0² + g1²`` for ``|∇e|``."""
    if code == PART_GRAD:
        return g0 * g0 + g1 * g1
    if code == PART_E:
        v = e
    elif code == PART_E_PLUS:
        v = max(e, 0.0)
    elif code == PART_E_MINUS:
        v = max(-e, 0.0)
    elif code == PART_D1:
        v = g0
    else:
        v = g1
    return v * v


@numba.njit(cache=True, inline="always")
def _power(s, p_int, p):  # pragma: no cover - compiled
    """``s^p``: for a positive integer ``p_int = p`` the product of the squarings of ``s`` at its set
    bits, in increasing order, as ``fem.norms.conventional.integer_power`` forms it (``1.0 · x`` is
    ``x``); else pow."""
    if p_int < 1:
        return s**p
    k, square, result = p_int, s, 1.0
    while k:
        if k & 1:
            result *= square
        k >>= 1
        if k:
            square = square * square
    return result


@numba.njit(cache=True, inline="always")
def _affine(px, py, v, a, b, c):  # pragma: no cover - compiled
    """The affine map of the triangle ``(a, b, c)``, ``J = [[j00, j01], [j10, j11]]``, its ``det J``
    and the gradient ``(g0, g1)`` of the P1 function ``v`` on it, as ``p1_at_points`` and
    ``fem.norms.true._Affine.of`` compute them."""
    j00, j01 = px[b] - px[a], px[c] - px[a]
    j10, j11 = py[b] - py[a], py[c] - py[a]
    det = j00 * j11 - j01 * j10
    d1, d2 = v[b] - v[a], v[c] - v[a]
    return j00, j01, j10, j11, det, (j11 * d1 - j10 * d2) / det, (-j01 * d1 + j00 * d2) / det


def squarings(p: float) -> int:
    """The ``p_int`` of ``_power`` for the exponent ``p``: ``p`` itself where ``integer_power`` forms
    the power by squarings (a positive integer), else 0 (pow)."""
    return int(p) if float(p).is_integer() and p >= 1 else 0


@numba.njit(cache=True, inline="always")
def _p1_triangle(px, py, t, v, el, role):  # pragma: no cover - compiled
    """Triangle ``el``'s vertices in the rule's order, ``|det J|`` and ``∇e = −∇v`` (``p1_at_points``)."""
    a, b, c = _rolled(px, py, t, el, role)
    _, _, _, _, det, g0, g1 = _affine(px, py, v, a, b, c)
    return a, b, c, abs(det), -g0, -g1


@numba.njit(cache=True)
def p1_rule_largest(px, py, t, v, X0, X1, role, parts):  # pragma: no cover - compiled
    """The largest ``|part|`` of ``e = −v`` (``v`` P1 on the mesh ``(px, py, t)``) over the points
    ``(X0, X1)`` of the rule placed on every triangle with ``role`` (−1: as stored)."""
    top = 0.0
    for el in range(t.shape[1]):
        a, b, c, _, g0, g1 = _p1_triangle(px, py, t, v, el, role)
        for j in range(parts.size):
            if parts[j] >= PART_D1:  # constant on the triangle
                top = max(top, _magnitude(parts[j], 0.0, g0, g1))
                continue
            for q in range(X0.size):
                e = -(v[a] * (1.0 - X0[q] - X1[q]) + v[b] * X0[q] + v[c] * X1[q])
                top = max(top, _magnitude(parts[j], e, g0, g1))
    return top


@numba.njit(cache=True)
def p1_rule_sum(px, py, t, v, X0, X1, W, role, parts, p_int, p, scale, constant):  # pragma: no cover - compiled
    """``Σ_T |det J_T| Σ_q W_q Σ_parts |part / scale|^p`` of ``e = −v``, the sum that
    ``fem.norms.conventional.field_p_sum`` reduces: per point the parts' powers added in order, the
    powers of the gradient parts (constant on a triangle) formed once per triangle (``constant``:
    scratch of the parts' size)."""
    total = 0.0
    for el in range(t.shape[1]):
        a, b, c, det, g0, g1 = _p1_triangle(px, py, t, v, el, role)
        for j in range(parts.size):
            if parts[j] >= PART_D1:
                constant[j] = _power(_magnitude(parts[j], 0.0, g0, g1) / scale, p_int, p)
        triangle = 0.0
        for q in range(W.size):
            e = -(v[a] * (1.0 - X0[q] - X1[q]) + v[b] * X0[q] + v[c] * X1[q])
            point = 0.0
            for j in range(parts.size):
                if parts[j] >= PART_D1:
                    term = constant[j]
                else:
                    term = _power(_magnitude(parts[j], e, g0, g1) / scale, p_int, p)
                point = term if j == 0 else point + term
            triangle += point * W[q]
        total += triangle * det
    return total


@numba.njit(cache=True)
def manufactured_rule_integrals(
    px, py, t, elements, u_h, X0, X1, w, x0, R, A, scale, parts, q_int, q, gradient, out
):  # pragma: no cover - compiled
    """``out[k] = ∫_T Σ_parts |part(e/scale, ∇e/scale)|^(2q)`` over the triangle ``T = elements[k]``
    of the mesh ``(px, py, t)`` by the rule of reference points ``(X0, X1)`` and weights ``w`` (summing
    to 1 over the reference triangle's doubled area), ``e = u − u_h`` with ``u_h`` affine on ``T``:
    ``fem.norms.true``'s plain rule in one pass over the points, the same operations per point (the
    sum over the points in order, where numpy's matrix–vector product takes its own)."""
    inverse = 1.0 / scale
    for k in range(elements.size):
        el = elements[k]
        a, b, c = t[0, el], t[1, el], t[2, el]
        v0x, v0y, u0 = px[a], py[a], u_h[a]
        j00, j01, j10, j11, det, g0, g1 = _affine(px, py, u_h, a, b, c)
        acc = 0.0
        for i in range(w.size):
            x = v0x + (j00 * X0[i] + j01 * X1[i])
            y = v0y + (j10 * X0[i] + j11 * X1[i])
            uh = u0 + g0 * (x - v0x) + g1 * (y - v0y)
            u, ux, uy = manufactured_point(x, y, x0, R, A, gradient)
            e = (u - uh) * inverse  # = (u - uh) / scale, bit for bit: scale is a power of two
            e0 = (ux - g0) * inverse
            e1 = (uy - g1) * inverse
            total = 0.0
            for j in range(parts.size):
                term = _power(_squared(parts[j], e, e0, e1), q_int, q)
                total = term if j == 0 else total + term
            acc += total * w[i]
        out[k] = acc * (abs(det) / 2.0)


@numba.njit(cache=True, inline="always")
def _edge_distance(ax, ay, bx, by, qx, qy):  # pragma: no cover - compiled
    """The distance of ``q`` to the segment ``ab``, as ``fem.norms.true._distance`` computes it."""
    abx, aby = bx - ax, by - ay
    s = ((qx - ax) * abx + (qy - ay) * aby) / (abx * abx + aby * aby)
    s = min(max(s, 0.0), 1.0)
    return math.hypot(ax + s * abx - qx, ay + s * aby - qy)


@numba.njit(cache=True)
def manufactured_survey(
    px, py, t, start, u_h, x0, R, A, exact_distance, gradient, largest, r_lo, r_hi, diameter
):  # pragma: no cover - compiled
    """Per triangle ``start + k`` of the mesh ``(px, py, t)``, into the k-th entry of each array:
    ``largest``, the largest of ``|e|`` (and ``|∂ₖe|`` if ``gradient``) at its centroid; ``r_lo``,
    ``r_hi`` and ``diameter`` as ``fem.norms.true._radii`` and ``_diameters`` give them for the
    singular point ``(x0, 0)`` (the same operations)."""
    for k in range(largest.size):
        el = start + k
        a, b, c = t[0, el], t[1, el], t[2, el]
        vx = (px[a], px[b], px[c])
        vy = (py[a], py[b], py[c])
        _, _, _, _, _, g0, g1 = _affine(px, py, u_h, a, b, c)
        cx = (vx[0] + vx[1] + vx[2]) / 3.0
        cy = (vy[0] + vy[1] + vy[2]) / 3.0
        uh = u_h[a] + g0 * (cx - vx[0]) + g1 * (cy - vy[0])
        u, ux, uy = manufactured_point(cx, cy, x0, R, A, gradient)
        big = abs(u - uh)
        if gradient:
            big = max(big, abs(ux - g0), abs(uy - g1))
        largest[k] = big
        d = max(
            math.hypot(vx[0] - vx[1], vy[0] - vy[1]),
            math.hypot(vx[1] - vx[2], vy[1] - vy[2]),
            math.hypot(vx[2] - vx[0], vy[2] - vy[0]),
        )
        diameter[k] = d
        h0 = math.hypot(vx[0] - x0, vy[0])
        h1 = math.hypot(vx[1] - x0, vy[1])
        h2 = math.hypot(vx[2] - x0, vy[2])
        nearest = min(h0, h1, h2)
        r_hi[k] = max(h0, h1, h2)
        lo = max(nearest - d, 0.0)
        if nearest < exact_distance * d:
            lo = min(
                _edge_distance(vx[0], vy[0], vx[1], vy[1], x0, 0.0),
                _edge_distance(vx[1], vy[1], vx[2], vy[2], x0, 0.0),
                _edge_distance(vx[2], vy[2], vx[0], vy[0], x0, 0.0),
            )
            inside_lo, inside_hi = math.inf, -math.inf
            for i in range(3):
                j = (i + 1) % 3
                cross = (vx[j] - vx[i]) * (0.0 - vy[i]) - (vy[j] - vy[i]) * (x0 - vx[i])
                inside_lo, inside_hi = min(inside_lo, cross), max(inside_hi, cross)
            if inside_lo >= 0.0 or inside_hi <= 0.0:
                lo = 0.0
        r_lo[k] = lo
