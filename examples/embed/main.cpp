// A program of one's own stepping an sphfem scene: it loads a scene file, steps it for a
// while and reads the particles. Usage: embed SCENE.json [SECONDS]
#include <sphfem/scene/load.h>
#include <sphfem/sim/simulation.h>

#include <cstdio>
#include <cstdlib>
#include <exception>

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s SCENE.json [SECONDS]\n", argv[0]);
    return 2;
  }
  const double seconds = argc > 2 ? std::atof(argv[2]) : 0.1;
  try {
    const sphfem::SceneSpec scene = sphfem::load_scene(argv[1]);
    sphfem::Simulation sim(scene, sphfem::Backend::Cpu);
    while (sim.time() < seconds) sim.step(scene.simulation.dt_max);

    sphfem::FluidSnapshot fluid;  // positions, velocities, densities of the particles
    sim.snapshot(fluid);
    double top = 0, front = 0;
    for (const sphfem::Vec3& x : fluid.x) {
      top = x.y > top ? x.y : top;
      front = x.x > front ? x.x : front;
    }
    std::printf(
        "t = %.4f s after %ld steps: %d particles, highest at y = %.4f m, front at "
        "x = %.4f m\n",
        sim.time(), sim.steps(), fluid.n, top, front);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
  return 0;
}
