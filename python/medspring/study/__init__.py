"""Parameter studies on Dask distributed (docs/studies.md): a study file names a base scene, the varied
quantities (grids, lists, seeded random or Latin-hypercube samples over any scene parameter path) and
what each run reports; `run` executes every run as part of a Dask task on the C++ engine in worker
processes and streams the results into a Zarr store and a summary CSV.

    from medspring import study
    df = study.run("examples/studies/kidney_stiffness.json", out="out/stiffness", workers=2)

The command line: `medspring study STUDY --out DIR [--scheduler tcp://HOST:PORT | --workers N]
[--resume] [--yes]` (or `python3 -m medspring.study ...`).
"""

from .run import connect, local_client, run
from .scaling import measure_scaling
from .spec import METRICS, Study, load_study

__all__ = ["run", "load_study", "Study", "METRICS", "connect", "local_client", "measure_scaling"]
