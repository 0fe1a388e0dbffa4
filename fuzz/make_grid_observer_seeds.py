#!/usr/bin/env python3
"""Writes the seed corpus of grid_observer_fuzzer to fuzz/corpus/grid_observer_fuzzer/.

The byte format is the one fuzz/grid_observer_property.h reads. The procedure, seeded so it is repeatable:
  * 5 grid shapes: 1-D with 8 and 16 points, 2-D with 8, 12 and 16 points per dimension;
  * for each shape, 6 healthy runs of 4 to 10 operations alternating Predict and Correct: a stable A
    (diagonal 0.5..1, small off-diagonal terms), B, G with entries k/16, an input u; a measurement of
    each kind (Gaussian, threshold, uniform quantiser, Laplace) with a positive parameter and a reading
    that is possible for it (threshold: -1, 0, 1; quantiser: a multiple of its step);
  * for each shape, 2 runs that also carry raw doubles: NaN, +-Inf, 1e308, 5e-324 in A, the noise, u, c
    and y, and a singular A.
That makes 5 x 8 = 40 inputs of 35 to 415 bytes.

Run from the repository root:  python3 fuzz/make_grid_observer_seeds.py
"""
import os
import random
import struct

OUT = os.path.join("fuzz", "corpus", "grid_observer_fuzzer")


def tame(k):
    """A value k/16 (k a signed byte): a kind byte that is not 0 mod 4, then k."""
    return bytes([1, k & 0xFF])


def raw(x):
    """Any double: a kind byte 0 mod 4, then its 8 bytes little-endian."""
    return bytes([0]) + struct.pack("<d", x)


def value(x):
    k = round(x * 16)
    assert -128 <= k <= 127 and k / 16 == x, x
    return tame(k)


def predict(rng, n, special=None):
    """Op byte (even; bit 1 clear: P_N = G G'), then A, B, G (column-major) and u."""
    out = bytes([0])
    for j in range(n):
        for i in range(n):
            a = rng.randint(8, 16) / 16 if i == j else rng.randint(-2, 2) / 16
            out += value(a)
    for i in range(n):
        out += value(rng.randint(-8, 8) / 16)
    for j in range(n):
        for i in range(n):
            out += value(rng.randint(1, 6) / 16 if i == j else 0.0)
    u = rng.randint(-16, 16) / 16
    if special is not None:
        return out + raw(special)  # the input u as a raw double
    return out + value(u)


def correct(rng, n, kind, special_y=None):
    """Op byte (odd), then c, the kind byte, the parameter and y."""
    out = bytes([1])
    for i in range(n):
        out += value(1.0 if i == 0 else rng.choice([0.0, 0.5]))
    out += bytes([kind])
    if kind == 0:    # Gaussian, noise variance
        out += value(rng.randint(1, 16) / 16) + value(rng.randint(-16, 16) / 16)
    elif kind == 1:  # threshold sensor, threshold T; y in {-1, 0, 1}
        out += value(rng.randint(4, 16) / 16) + value(rng.choice([-1.0, 0.0, 0.0, 1.0]))
    elif kind == 2:  # uniform quantiser, step 0.25; y a multiple of it
        out += value(0.25) + value(rng.randint(-4, 4) * 0.25)
    else:            # Laplace, scale
        out += value(rng.randint(2, 16) / 16) + value(rng.randint(-16, 16) / 16)
    if special_y is not None:
        out = out[:-2] + raw(special_y)
    return out


def main():
    rng = random.Random(20261123)
    os.makedirs(OUT, exist_ok=True)
    shapes = [(1, 8), (1, 16), (2, 8), (2, 12), (2, 16)]
    for n, points in shapes:
        shape = bytes([(n - 1) | ((points - 8) << 1)])
        for run in range(6):
            data = shape
            for step in range(rng.randint(2, 5)):
                data += predict(rng, n) + correct(rng, n, (run + step) % 4)
            with open(os.path.join(OUT, f"seed-n{n}-p{points}-{run}"), "wb") as f:
                f.write(data)
        specials = [float("nan"), float("inf"), -float("inf"), 1e308, 5e-324]
        for run in range(2):
            data = shape + predict(rng, n)
            for k, x in enumerate(specials):
                data += predict(rng, n, special=x) + correct(rng, n, (run + k) % 4, special_y=x)
            # A singular A (all zeros), then a healthy step, then raw doubles for every entry of A.
            data += bytes([0]) + value(0.0) * (n * n + n + n * n + 1) + predict(rng, n) + correct(rng, n, 0)
            data += bytes([2]) + b"".join(raw(rng.choice(specials)) for _ in range(n * n + n + n * n + 1))
            with open(os.path.join(OUT, f"special-n{n}-p{points}-{run}"), "wb") as f:
                f.write(data)


if __name__ == "__main__":
    main()
