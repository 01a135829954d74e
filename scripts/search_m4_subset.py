#!/usr/bin/env python3
"""The m = 4 candidate subset of docs/search.md ("Rerun with the certified LP"), comma separated
for `momentlab search --m 4 --candidates`.

Candidates are numbered in colexicographic order (src/basis/candidates.rs): the index of the
sorted catalog positions s_1 < … < s_4 is sum_i C(s_i, i). The subset: 3 300 indices drawn
uniformly (Python's random, seed 1), b_MSM (0), b_TMSM (40860), the earlier full-sweep winner
57781, and the forward extensions of the m = 3 winner (exp(-20z), exp(40z), exp(-40z)) by one
function and of the m = 2 winner (exp(40z), tanh(10(z-0.5))) by two: 3 899 candidates.
"""
import itertools
import random
from math import comb

N = 37  # functions in basis_functions/catalog.json


def index(subset):
    return sum(comb(c, i + 1) for i, c in enumerate(sorted(subset)))


def subset():
    random.seed(1)
    sel = set(random.sample(range(comb(N, 4)), 3300))
    sel |= {0, 40860, 57781}
    w3 = (14, 15, 16)  # exp(-20z), exp(40z), exp(-40z)
    sel |= {index(w3 + (k,)) for k in range(N) if k not in w3}
    w2 = (15, 34)  # exp(40z), tanh(10(z-0.5))
    rest = [k for k in range(N) if k not in w2]
    sel |= {index(w2 + pair) for pair in itertools.combinations(rest, 2)}
    return sorted(sel)


if __name__ == "__main__":
    print(",".join(map(str, subset())))
