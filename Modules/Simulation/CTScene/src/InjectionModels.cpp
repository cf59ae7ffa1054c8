// The built-in injection engines: one line each (InjectionModel.h). A new engine is a folder under
// src/Models/ with a factory and the scene keys it reads, and one line here.
#include "cementsph/scene/InjectionModel.h"

namespace cementsph::scene {

std::unique_ptr<InjectionModel> makeParticleInjectionModel();   // src/Models/Particles
std::unique_ptr<InjectionModel> makeVoxelDarcyInjectionModel(); // src/Models/VoxelDarcy
std::unique_ptr<InjectionModel> makeParticleDarcyInjectionModel(); // src/Models/ParticleDarcy
InjectionModelRegistry::SceneKeys particleSceneKeys();
InjectionModelRegistry::SceneKeys voxelDarcySceneKeys();
InjectionModelRegistry::SceneKeys particleDarcySceneKeys();

void registerBuiltInInjectionModels(InjectionModelRegistry& r) {
  r.add("voxel-darcy", makeVoxelDarcyInjectionModel, "incompressible-darcy-on-voxels", voxelDarcySceneKeys());
  r.add("incompressible", makeParticleInjectionModel, "incompressible-darcy-on-particles", particleSceneKeys());
  r.add("equation-of-state", makeParticleInjectionModel, "weakly-compressible", particleSceneKeys());
  r.add("particle-darcy", makeParticleDarcyInjectionModel, "incompressible-darcy-on-particles-isph",
        particleDarcySceneKeys());
}

} // namespace cementsph::scene
