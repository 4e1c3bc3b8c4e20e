// Every rendering method Lucent has, by name: what `lucent render --method NAME` and a scene
// file's render block choose from, and how another program renders with any of them.
#pragma once
#include <string>
#include <vector>

#include "lucent/pipeline/method.h"

namespace lucent {

// In the order `lucent methods` lists them.
const std::vector<const Method*>& renderingMethods();

// The method of that name; throws std::invalid_argument naming the available ones.
const Method& renderingMethod(const std::string& name);

// The method that declares an option of that name, other than `except`; nullptr if none.
const Method* methodWithOption(const std::string& option, const Method* except = nullptr);

}  // namespace lucent
