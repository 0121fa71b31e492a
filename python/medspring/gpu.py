"""medspring.gpu: the CUDA backend from Python (docs/gpu.md).

B spring networks of the same topology (surface bodies, the hybrid kidney) stepped together on an NVIDIA
GPU with the CPU engine's physics, substep rule and guard; states as (B, N, 3) NumPy arrays, the device
state handed zero-copy to CuPy / PyTorch through DLPack:

    import medspring as ms, medspring.gpu as gpu
    kidney = ms.hybrid_kidney_phantom()
    e = gpu.Engine([kidney.model] * 2048)                 # fp64; one thread block per model here
    e.set_loads(0, [ms.PointLoad(node=223, force=(0, 0, -1.0))])
    e.step(frames=1000)
    x = e.positions()                                     # (2048, 500, 3) float64 copy
    xt = torch.from_dlpack(e)                             # the device positions, no copy

Without a CUDA backend in the build (MEDSPRING_CUDA) or without a device, `Engine(...)` and
`require_device()` raise GpuError saying why and naming the CPU engine; `built()` tells the first case.
"""

from __future__ import annotations

from . import _medspring

_gpu = getattr(_medspring, "_gpu", None)

_NOT_BUILT = (
    "GPU: this build of MedSpring has no CUDA backend (configure with -DMEDSPRING_CUDA=ON where nvcc is "
    "installed, docs/gpu.md); use the CPU engine (medspring.step, medspring.Simulation)"
)

if _gpu is not None:
    GpuError = _gpu.GpuError
    Engine = _gpu.Engine
    require_supported = _gpu.require_supported
else:

    class GpuError(_medspring.Error, RuntimeError):
        """A GPU-side failure: no CUDA backend in the build, no device, a driver older than the runtime, out
        of device memory, a model feature the GPU path lacks. The message names the CPU alternative."""

    class Engine:  # noqa: D101 -- the stand-in of a build without CUDA
        def __init__(self, *args, **kwargs):
            raise GpuError(_NOT_BUILT)

    def require_supported(kind: str, local_overlay: bool = False, tools: bool = False) -> None:
        raise GpuError(_NOT_BUILT)


def built() -> bool:
    """True when this build has the CUDA backend."""
    return _gpu is not None


def require_device(index: int = 0) -> dict:
    """The device `index` (name, compute capability, memory, ...) or GpuError saying why it cannot be used
    (no CUDA backend in the build, no driver, no device, a driver too old, compute capability < 9.0)."""
    if _gpu is None:
        raise GpuError(_NOT_BUILT)
    return _gpu.require_device(index)


def available(index: int = 0) -> tuple[bool, str]:
    """(True, device name) when the device can be used, else (False, the reason): for skipping."""
    try:
        return True, require_device(index)["name"]
    except GpuError as e:
        return False, str(e)


__all__ = ["Engine", "GpuError", "available", "built", "require_device", "require_supported"]
