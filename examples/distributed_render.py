"""Render a scene on a Dask cluster and check it against a local render.

    pip install 'niebla[distributed]'
    python examples/distributed_render.py                      # a LocalCluster here
    python examples/distributed_render.py tcp://host:8786      # a running scheduler

The distributed image is bit for bit the one-process render of the same
scene, seed and samples (niebla adds exact per-pixel sums of sample ranges).
"""

import sys
from pathlib import Path

import numpy as np

import niebla
import niebla.distributed as nd
from dask.distributed import Client, LocalCluster

SCENE = Path(__file__).resolve().parents[1] / "scenes" / "default.json"


def main() -> None:
    if len(sys.argv) > 1:
        client = Client(sys.argv[1])
    else:
        client = Client(LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=None))
    # For SLURM: from dask_jobqueue import SLURMCluster; cluster = SLURMCluster(cores=8, memory="8GB");
    # cluster.scale(jobs=4); client = Client(cluster)
    spp = 16
    result = nd.render(SCENE, spp=spp, chunk_spp=3, client=client, checkpoint="default_partial.exr")
    niebla.write_exr(result.image(), "default_distributed.exr")
    local = niebla.Scene.from_file(SCENE).render(spp=spp, progress=False)
    same = np.array_equal(result.image().view(np.uint32), local.view(np.uint32))
    print(f"{result.spp} spp in {len(result.ranges)} range(s) {result.ranges}; bit-identical to a local render: {same}")
    client.close()


if __name__ == "__main__":
    main()
