// The random numbers a path takes: independent ones, or a padded Owen-scrambled Sobol sequence
// (core/path_sampler.h).
#pragma once

namespace lucent {

enum class SamplerKind { Independent, Sobol };

}  // namespace lucent
