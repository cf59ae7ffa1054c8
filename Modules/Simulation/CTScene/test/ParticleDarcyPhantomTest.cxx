// Issue 19's phantom oracle for the incompressible SPH (pressure_model "particle-darcy") at 1 ml against the voxel
// model (ParticleDarcyPhantom.h: Dice >= 0.85, spreading within 0.5 mm, tip pressure within 15 %). About 8 s of CPU
// (one thread) since the multi-rate stepping. PARTICLE_DARCY_PHANTOM_ML sets another volume by hand.
#include "ParticleDarcyPhantom.h"

TEST(ParticleDarcyPhantom, ParticlesAgreeWithTheVoxelModelOnTheBundledPhantom) {
  particle_darcy_phantom::expectParticlesAgreeWithTheVoxelModel(particle_darcy_phantom::envOr("PARTICLE_DARCY_PHANTOM_ML", 1.0));
}
