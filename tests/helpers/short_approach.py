"""A short rendered approach (1.5-1.8 km out, a few dozen frames): the datasets tests' common input.

``visland generate``'s job for a scenario a little off the centreline and below the glide path,
at a small size and frame rate; its labels.csv and truth.csv are the exact answers.
"""
from visland.camera import CameraModel
from visland.datasets import generate as gen
from visland.render.params import SceneParams
from visland.scenarios import Scenario
from visland.simulate import SimulationOptions


def short_job(size: int, fps: float, dx_m: float = -1500.0, dy_m: float = 25.0, dgs_m: float = -5.0,
              dpsi_deg: float = 2.0, seed: int = 1) -> gen.GenerateJob:
    """The generate job of a short approach (scenario ``short``, glide slope -3 deg, scene and noise
    seeded with ``seed``) seen by the SPEC camera scaled to ``size`` pixels at ``fps``."""
    scenario = Scenario("short", dx_m=dx_m, dy_m=dy_m, dgs_m=dgs_m, dpsi_deg=dpsi_deg, gamma_deg=-3.0)
    options = SimulationOptions(fps=fps, camera=CameraModel.default(size), seed=seed)
    return gen.GenerateJob(scenario, options, SceneParams(seed=seed))


def generate_short(out, size: int, fps: float, **kwargs):
    """Render :func:`short_job` into the folder ``out`` (``visland generate``); return ``out``."""
    gen.generate_dataset(short_job(size, fps, **kwargs), out, progress=False)
    return out
