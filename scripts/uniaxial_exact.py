#!/usr/bin/env python3
"""Exact homogeneous uniaxial solution of the paper's eq. (1) (Ogden; neo-Hookean is alpha = 2), free sides.

Prints the top-face force (N) of a cube of side L compressed to axial stretch s:
    python3 scripts/uniaxial_exact.py --mu 722 --alpha -1.3 --D 5.57738e-5 --stretch 0.8 --side 0.01
The lateral stretch is found by bisection so that the lateral nominal stress vanishes; stresses are
central differences of the energy (as tests/scenes/verification_test.cpp does, written independently).
Used to generate the reference values of share/studies/stability.json.
"""
import argparse


def energy(mu, alpha, D):
    def W(l):
        J = l[0] * l[1] * l[2]
        s = J ** (-1.0 / 3.0)
        return 2.0 * mu / alpha ** 2 * sum((s * x) ** alpha - 1.0 for x in l) + (J - 1.0) ** 2 / D
    return W


def nominal(W, l, i, h=1e-6):
    a, b = list(l), list(l)
    a[i] += h
    b[i] -= h
    return (W(a) - W(b)) / (2 * h)


def top_force(mu, alpha, D, stretch, side):
    W = energy(mu, alpha, D)
    lo, hi = 0.5, 2.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if nominal(W, [mid, mid, stretch], 0) > 0:
            hi = mid
        else:
            lo = mid
    return nominal(W, [lo, lo, stretch], 2) * side * side


if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--mu", type=float, required=True)
    p.add_argument("--alpha", type=float, default=2.0)
    p.add_argument("--D", type=float, required=True)
    p.add_argument("--stretch", type=float, default=0.8)
    p.add_argument("--side", type=float, default=0.01)
    a = p.parse_args()
    print("%.9g" % top_force(a.mu, a.alpha, a.D, a.stretch, a.side))
