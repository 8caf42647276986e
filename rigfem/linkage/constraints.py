"""The constraint equations of a planar linkage: residual Phi(q, theta), Jacobian Phi_q and
the right-hand side gamma of Phi_q qddot = gamma, vectorised over crank angles.

Coordinates: per moving body the global position of its frame origin and the angle of its
x axis, q = (x, y, phi) (SI inside: m, rad).  The ground is fixed at the origin with zero
angle and has no coordinates.  With one driver constraint the Jacobian is square.
"""

from __future__ import annotations

import numpy as np

from rigfem.errors import ComputeError
from rigfem.linkage.model import GROUND, CrankDriver, Linkage, Prismatic, Revolute, SliderDriver, perp

__all__ = ["Constraints", "dot"]

_ZERO2, _ZERO1 = np.zeros((1, 2)), np.zeros(1)        # the ground's pose, broadcast over samples


def dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise dot product, (..., 2) · (..., 2) -> (...)."""
    return np.einsum("...i,...i->...", a, b)


class Constraints:
    """Index bookkeeping and vectorised constraint evaluation for one Linkage (SI units)."""

    def __init__(self, lk: Linkage):
        self.lk = lk
        names = [b.name for b in lk.bodies]
        if GROUND in names or len(set(names)) != len(names):
            raise ComputeError("body names must be unique and not 'ground'")
        self.index = {n: i for i, n in enumerate(names)}
        self.nb = len(names)
        self.m = 3 * self.nb
        rows, r = [], 0
        for j in lk.joints:
            for b in (j.body_a, j.body_b):
                if b != GROUND and b not in self.index:
                    raise ComputeError(f"joint {j.name}: unknown body {b!r}")
            rows.append(r)
            r += 2
        self.rows = rows
        self.drow = r
        if r + 1 != self.m:
            raise ComputeError(f"linkage has {self.nb} bodies and {r} joint constraints + 1 driver: "
                             f"not a one-degree-of-freedom linkage")
        self.jidx = {j.name: k for k, j in enumerate(lk.joints)}
        self.loc = {j.name: (np.asarray(j.local_a_mm, float) / 1000, np.asarray(j.local_b_mm, float) / 1000)
                    for j in lk.joints}
        if isinstance(lk.driver, SliderDriver):
            if lk.driver.joint not in self.jidx or not isinstance(lk.joints[self.jidx[lk.driver.joint]], Prismatic):
                raise ComputeError(f"slider driver: {lk.driver.joint!r} is not a prismatic joint")
        elif lk.driver.body not in self.index:
            raise ComputeError(f"crank driver: unknown body {lk.driver.body!r}")
        pts = [np.asarray(p, float) for j in lk.joints for p in (j.local_a_mm, j.local_b_mm)]
        self.scale = max(1e-3, max((np.hypot(*p) for p in pts), default=1.0) / 1000, *(
            np.hypot(g[0], g[1]) / 1000 for g in lk.guess.values()))

    # -- pose access
    def pose(self, q: np.ndarray, body: str):
        """(r (n,2), phi (n,)) of a body; ground -> zeros of shape (1, 2), (1,) (broadcasting)."""
        if body == GROUND:
            return _ZERO2, _ZERO1
        i = 3 * self.index[body]
        return q[:, i:i + 2], q[:, i + 2]

    def cols(self, body: str):
        return None if body == GROUND else 3 * self.index[body]

    # -- driver target
    def drive(self, theta: np.ndarray):
        """Driver value and its first and second derivatives by the phase at phase theta (rad;
        SI): the driver's law, which knows no speed (rates: times omega and omega²)."""
        d = self.lk.driver
        if isinstance(d, CrankDriver):
            return theta + d.offset_rad, np.ones_like(theta), np.zeros_like(theta)
        a = d.amplitude_mm / 1000
        return d.mean_mm / 1000 + a * np.sin(theta), a * np.cos(theta), -a * np.sin(theta)

    def frame(self, q: np.ndarray) -> dict:
        """Per-joint rotated local vectors (and prismatic axis, normal, gap) at positions q."""
        n_s = q.shape[0]
        C, S = np.cos(q[:, 2::3]), np.sin(q[:, 2::3])

        def rot(body, s):
            if body == GROUND:
                return s[None, :]
            k = self.index[body]
            out = np.empty((n_s, 2))
            out[:, 0] = C[:, k] * s[0] - S[:, k] * s[1]
            out[:, 1] = S[:, k] * s[0] + C[:, k] * s[1]
            return out

        fr = {}
        for j in self.lk.joints:
            sa, sb = rot(j.body_a, self.loc[j.name][0]), rot(j.body_b, self.loc[j.name][1])
            if isinstance(j, Revolute):
                fr[j.name] = (sa, sb)
            else:
                ra, _ = self.pose(q, j.body_a)
                rb, _ = self.pose(q, j.body_b)
                ax = np.asarray(j.axis_a, float)
                u = rot(j.body_a, ax / np.hypot(*ax))
                fr[j.name] = (sa, sb, u, perp(u), rb + sb - ra - sa)
        return fr

    def residual(self, q: np.ndarray, theta: np.ndarray, fr: dict | None = None) -> np.ndarray:
        fr = fr if fr is not None else self.frame(q)
        n_s = q.shape[0]
        res = np.empty((n_s, self.m))
        for j, r in zip(self.lk.joints, self.rows):
            _, pa = self.pose(q, j.body_a)
            _, pb = self.pose(q, j.body_b)
            if isinstance(j, Revolute):
                ra, _ = self.pose(q, j.body_a)
                rb, _ = self.pose(q, j.body_b)
                sa, sb = fr[j.name]
                res[:, r:r + 2] = ra + sa - rb - sb
            else:
                _, _, _, n, d = fr[j.name]
                res[:, r] = dot(n, d)
                res[:, r + 1] = pb - pa - j.rel_angle_rad
        target = self.drive(theta)[0]
        dv = self.lk.driver
        if isinstance(dv, CrankDriver):
            res[:, self.drow] = self.pose(q, dv.body)[1] - target
        else:
            _, _, u, _, d = fr[dv.joint]
            res[:, self.drow] = dot(u, d) - target
        return res

    def jacobian(self, q: np.ndarray, fr: dict | None = None) -> np.ndarray:
        fr = fr if fr is not None else self.frame(q)
        n_s = q.shape[0]
        J = np.zeros((n_s, self.m, self.m))
        for j, r in zip(self.lk.joints, self.rows):
            ca, cb = self.cols(j.body_a), self.cols(j.body_b)
            if isinstance(j, Revolute):
                sa, sb = fr[j.name]
                if ca is not None:
                    J[:, r, ca] = J[:, r + 1, ca + 1] = 1.0
                    J[:, r:r + 2, ca + 2] = perp(sa)
                if cb is not None:
                    J[:, r, cb] = J[:, r + 1, cb + 1] = -1.0
                    J[:, r:r + 2, cb + 2] = -perp(sb)
            else:
                self._prism_rows(J, r, fr[j.name], ca, cb, normal=True)
                if ca is not None:
                    J[:, r + 1, ca + 2] = -1.0
                if cb is not None:
                    J[:, r + 1, cb + 2] = 1.0
        dv = self.lk.driver
        if isinstance(dv, CrankDriver):
            J[:, self.drow, self.cols(dv.body) + 2] = 1.0
        else:
            j = self.lk.joints[self.jidx[dv.joint]]
            self._prism_rows(J, self.drow, fr[j.name], self.cols(j.body_a), self.cols(j.body_b), normal=False)
        return J

    @staticmethod
    def _prism_rows(J, r, terms, ca, cb, normal: bool):
        """Row of n·d (normal=True) or u·d (the sliding coordinate)."""
        sa, sb, u, n, d = terms
        v, dv = (n, -u) if normal else (u, n)      # d v / d phi_a
        if ca is not None:
            J[:, r, ca:ca + 2] = -v
            J[:, r, ca + 2] = dot(dv, d) - dot(v, perp(sa))
        if cb is not None:
            J[:, r, cb:cb + 2] = v
            J[:, r, cb + 2] = dot(v, perp(sb))

    def gamma(self, q: np.ndarray, qd: np.ndarray, sdd: np.ndarray, fr: dict | None = None) -> np.ndarray:
        """Right-hand side of Phi_q qddot = gamma (quadratic velocity terms)."""
        fr = fr if fr is not None else self.frame(q)
        n_s = q.shape[0]
        g = np.zeros((n_s, self.m))
        for j, r in zip(self.lk.joints, self.rows):
            _, wa = self.pose(qd, j.body_a)
            _, wb = self.pose(qd, j.body_b)
            if isinstance(j, Revolute):
                sa, sb = fr[j.name]
                g[:, r:r + 2] = sa * (wa**2)[:, None] - sb * (wb**2)[:, None]
            else:
                g[:, r] = self._prism_gamma(qd, j, fr[j.name], normal=True)
        dv = self.lk.driver
        if isinstance(dv, CrankDriver):
            g[:, self.drow] = sdd
        else:
            j = self.lk.joints[self.jidx[dv.joint]]
            g[:, self.drow] = sdd + self._prism_gamma(qd, j, fr[j.name], normal=False)
        return g

    def _prism_gamma(self, qd, j, terms, normal: bool) -> np.ndarray:
        sa, sb, u, n, d = terms
        va, wa = self.pose(qd, j.body_a)
        vb, wb = self.pose(qd, j.body_b)
        dd = vb + perp(sb) * wb[:, None] - va - perp(sa) * wa[:, None]
        v, w = (n, u) if normal else (u, -n)        # v' = -w * wa   (n' = -u wa, u' = n wa)
        return (wa**2 * dot(v, d) + 2 * wa * dot(w, dd)
                + dot(v, sb * (wb**2)[:, None] - sa * (wa**2)[:, None]))
