// Issue 19's phantom oracle at 5 ml (the second volume; ParticleDarcyPhantom.h: Dice >= 0.85, spreading
// within 0.5 mm, tip pressure within 15 % of the voxel model's). Label slow: about 100 s of CPU for the particles
// (one thread), 1 s for the voxel model. Before the step's speed was capped (the density correction's feedback
// on the step) this run never ended.
#include "ParticleDarcyPhantom.h"

TEST(ParticleDarcyPhantom5ml, ParticlesAgreeWithTheVoxelModelOnTheBundledPhantomAt5Ml) {
  particle_darcy_phantom::expectParticlesAgreeWithTheVoxelModel(5.0);
}
