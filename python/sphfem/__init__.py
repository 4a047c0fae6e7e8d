"""sphfem: SPH fluid coupled with FEM soft bodies, from Python.

    import sphfem
    sim = sphfem.Simulation("scenes/dam_break.json")
    sim.advance(0.1)
    print(sim.n_particles, sim.positions[:, 1].max(), sim.gauges["kinetic_energy"][-1])

Which arrays are copies, how steps line up with `sphfem run`, and every method: docs/python.md.
"""

from ._sphfem import (
    CheckpointError,
    SceneError,
    Simulation,
    SimulationError,
    load_scene,
)

__all__ = ["CheckpointError", "SceneError", "Simulation", "SimulationError", "load_scene"]
