"""The quasi-static linear response from Python (ms.LinearResponse, docs/linear-response.md)."""

import numpy as np
import pytest

import medspring as ms


def test_linear_response_from_python_is_k0_inverse():
    """ms.LinearResponse (docs/linear-response.md) on the hybrid kidney phantom's model (return springs hold
    it): positions(f) solves K0 u = f over the free nodes, the compliance blocks are symmetric and the
    response superposes; float and double columns agree to float rounding."""
    model = ms.hybrid_kidney_phantom().model
    n = model.x0.shape[0]
    R = ms.LinearResponse(model)
    assert R.num_nodes == n and R.factor_nonzeros > 0 and R.direct_threshold >= 1
    f = np.zeros((n, 3))
    f[223] = [0.0, 0.0, -0.5]
    x = R.positions(f)
    assert R.cached(223) and R.cached_nodes == 1
    K = ms.tangent_stiffness(model, model.x0)
    r = K @ (x - model.x0).ravel() - f.ravel()
    assert np.abs(r).max() < 1e-6 * 0.5  # float columns: K0 u = f to float rounding
    C = R.block(223, 40)
    assert np.allclose(C, R.block(40, 223).T, rtol=0, atol=1e-6 * np.abs(R.block(223, 223)).max())
    g = np.zeros((n, 3))
    g[40] = [0.1, 0.2, 0.0]
    both = R.positions(f + g)
    assert np.abs(both - (x + R.positions(g) - model.x0)).max() < 1e-9
    exact = ms.LinearResponse(model, precision="double").positions(f)
    assert np.abs(exact - x).max() < 1e-6 * np.abs(x - model.x0).max()
    with pytest.raises(ms.InvalidInput, match="precision"):
        ms.LinearResponse(model, precision="half")
