"""medspring.gpu (docs/gpu.md): batches as (B, N, 3) arrays and DLPack hand-over. The tests that need a
device skip with the reason the engine gives; the error tests run everywhere."""

import numpy as np
import pytest

import medspring as ms
import medspring.gpu as gpu

HAVE_DEVICE, WHY = gpu.available()
needs_device = pytest.mark.skipif(not HAVE_DEVICE, reason=f"no usable CUDA device: {WHY}")


def press(node, force, release=2500.0):
    return [ms.PointLoad(node=node, force=force, t_ramp=10.0, t_release=release)]


def test_built_says_whether_the_module_has_the_cuda_backend():
    assert gpu.built() == bool(ms._medspring.has_gpu)


def test_gpu_error_is_a_medspring_error_and_a_runtime_error():
    assert issubclass(gpu.GpuError, ms.Error)
    assert issubclass(gpu.GpuError, RuntimeError)


@pytest.mark.skipif(HAVE_DEVICE, reason="a device is present")
def test_without_a_device_the_engine_is_refused_naming_the_cpu_engine():
    kidney = ms.hybrid_kidney_phantom()
    with pytest.raises(gpu.GpuError) as e:
        gpu.Engine([kidney.model])
    msg = str(e.value)
    assert msg.startswith("GPU:"), msg
    assert "CPU engine" in msg, msg
    assert len(msg.splitlines()) == 1
    with pytest.raises(gpu.GpuError):
        gpu.require_device()
    ok, why = gpu.available()
    assert not ok and why == msg


@pytest.mark.skipif(not gpu.built(), reason="this build has no CUDA backend")
def test_unsupported_kinds_name_the_cpu_alternative():
    with pytest.raises(gpu.GpuError, match="CPU engine"):
        gpu.require_supported("smrm")
    gpu.require_supported("hybrid")


@needs_device
def test_batch_of_kidneys_as_bn3_arrays_follows_the_cpu_step():
    kidney = ms.hybrid_kidney_phantom()
    m = kidney.model
    B = 3
    e = gpu.Engine([m] * B)
    assert (e.batch, e.nodes) == (B, m.num_nodes)
    loads = [press(50 + 100 * b, (0.0, 0.1 * b, -0.2 - 0.2 * b)) for b in range(B)]
    for b in range(B):
        e.set_loads(b, loads[b])
    settings = ms.StepSettings()
    states = [ms.make_state(m) for _ in range(B)]
    for b in range(B):
        ms.step(m, states[b], settings, loads[b], nsteps=300)
    e.step(frames=300)
    x = e.positions()
    assert x.shape == (B, m.num_nodes, 3) and x.dtype == np.float64
    for b in range(B):
        scale = max(1.0, np.abs(states[b].x).max())
        assert np.abs(x[b] - states[b].x).max() / scale <= 1e-12
    assert e.velocities().shape == (B, m.num_nodes, 3)


@needs_device
def test_upload_checks_the_shape_and_round_trips():
    kidney = ms.hybrid_kidney_phantom()
    e = gpu.Engine([kidney.model] * 2)
    x = e.positions() + 0.5
    e.upload(x)
    assert np.array_equal(e.positions(), x)
    with pytest.raises(ms.InvalidInput, match=r"x: expected a C-contiguous float64 array of shape \(2, 500, 3\)"):
        e.upload(x[:1])


@needs_device
def test_haptic_node_read_and_dlpack_hand_over():
    kidney = ms.hybrid_kidney_phantom()
    e = gpu.Engine([kidney.model] * 2)
    e.set_loads(1, press(223, (0.0, 0.0, -1.0)))
    e.step(frames=50)
    x = e.positions()
    e.request_node(1, 223)
    got = None
    for _ in range(2000):
        got = e.poll_node()
        if got is not None:
            break
    assert got is not None and np.array_equal(got, x[1, 223])
    assert e.__dlpack_device__() == (2, 0)
    torch = pytest.importorskip("torch")
    t = torch.from_dlpack(e)
    assert tuple(t.shape) == (2, kidney.model.num_nodes, 3) and t.is_cuda
    assert np.array_equal(t.cpu().numpy(), x)
