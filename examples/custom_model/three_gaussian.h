// A kernel model defined outside ssslab: "three_gaussian" (and "three_gaussian:widths=N").
#pragma once

namespace custom {

/// Adds "three_gaussian" to ssslab's name -> factory table (approx/model_spec.h).
void register_three_gaussian();

}  // namespace custom
