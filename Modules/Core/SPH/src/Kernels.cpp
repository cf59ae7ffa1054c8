// The kernels are inline (Kernels.h); this unit checks the header compiles on its own.
#include "cementsph/sph/Kernels.h"
