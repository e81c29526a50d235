import sys

import numpy as np

sys.path.insert(0, "/work/wt/scale-audit/tests/envs")
import test_set_observation as t

for n in (9, 24, 32, 64):
    eng = t._engine(n, steps=30)
    eng.current.flying[1, 1] = False
    got = eng.observe()
    want = t._reference(eng)
    err = np.abs(got[..., t.B["role"].start :] - want).max()
    rows = got[..., t.B["neighbours"]].reshape(2, n, t.K, t.W)
    print(n, "max err", err, "mask rows per UAV", np.unique(rows[..., -1].sum(-1)))
