#!/usr/bin/env python3
"""Golden data for sitar-estimator's exact sums (rust/estimator/src/exact.rs).

Writes rust/estimator/tests/data/golden_exact_sums.json: lists of doubles (as their IEEE bit
patterns, so nothing is lost in JSON) with
  fsum        the correctly rounded exact sum: math.fsum (Shewchuk's algorithm), checked
              against the exact rational sum (fractions) rounded by true division
  std         the population standard deviation from exact rational arithmetic
              (fractions), its square root taken with 60 significant digits and then rounded
              to a double (absent where the values are signed or the variance overflows)
  numpy_std   numpy.std of the same values (two-pass, in doubles)
Deterministic (fixed seed). Usage: python3 scripts/golden/make_exact_sums.py (needs numpy).
"""
import decimal
import json
import math
import pathlib
import struct
from fractions import Fraction

import numpy as np

OUT = pathlib.Path(__file__).resolve().parents[2] / "rust" / "estimator" / "tests" / "data"
rng = np.random.default_rng(20260514)


def bits(x):
    return struct.unpack("<Q", struct.pack("<d", float(x)))[0]


def exact_std(values):
    n = len(values)
    exact = [Fraction(v) for v in values]
    mean = sum(exact) / n
    variance = sum((v - mean) ** 2 for v in exact) / n
    with decimal.localcontext() as context:
        context.prec = 60
        root = (decimal.Decimal(variance.numerator) / decimal.Decimal(variance.denominator)).sqrt()
    return float(root)


def case(name, values, with_std=True):
    values = [float(v) for v in values]
    exact = float(sum(Fraction(v) for v in values))
    if max(abs(v) for v in values) < 1e307:  # fsum overflows near the largest double
        assert math.fsum(values) == exact, name
    out = {"name": name, "bits": [bits(v) for v in values], "fsum": bits(exact)}
    if with_std:
        out["std"] = bits(exact_std(values))
        out["numpy_std"] = bits(np.std(np.array(values)))
    return out


def main():
    cases = [
        case("pair values, centimetres", np.abs(rng.normal(0.03, 0.01, 2000))),
        case("a spread far below the mean", 1e8 + rng.random(1000)),
        case("a spread 1e-12 of the mean", 1.0 + 1e-12 * rng.random(500)),
        case("all equal", [0.1] * 777),
        case("zeros and one value", [0.0] * 100 + [2.5]),
        case("subnormals", [5e-324 * k for k in range(1, 200)] + [2.2250738585072014e-308]),
        case("tiny and large", np.concatenate([rng.random(50) * 1e-200, rng.random(50) * 1e100])),
        case("every binade", [2.0 ** k * (1 + rng.random()) for k in range(-1074, 1000, 7)], with_std=False),
        case("near the largest double", [1.7976931348623157e308, 1e308, -1e308, -9.9e307], with_std=False),
        case("cancellation", [1e100, 1.0, -1e100, 1e-100, 3.3, -3.3, 2.0 ** -60], with_std=False),
        case("signed noise", rng.normal(0, 1, 2000) * 10.0 ** rng.integers(-20, 20, 2000), with_std=False),
        case("ties to even", [1.0, 2.0 ** -53, 1.0, 2.0 ** -52, 2.0 ** -53], with_std=False),
    ]
    path = OUT / "golden_exact_sums.json"
    path.write_text(json.dumps({"cases": cases}, separators=(",", ":")) + "\n")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
