// Precompiled header of comorph_perception's torch sources (CMakeLists.txt).
#pragma once
#include <torch/torch.h>
