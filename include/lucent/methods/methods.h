// Every rendering method Lucent has, by name: what `lucent render --method NAME` and a scene
// file's render block choose from, and how another program renders with any of them.
#pragma once
#include <string>
#include <vector>

#include "lucent/pipeline/method.h"
#include "lucent/scene/scene.h"

namespace lucent {

// In the order `lucent methods` lists them.
const std::vector<const Method*>& renderingMethods();

// The method of that name; throws std::invalid_argument naming the available ones.
const Method& renderingMethod(const std::string& name);

// The method that declares an option of that name, other than `except`; nullptr if none.
const Method* methodWithOption(const std::string& option, const Method* except = nullptr);

// Throws std::invalid_argument, `where` first, if `method` has no option `name` (naming the method
// that has it, if one does).
void checkMethodOption(const Method& method, const std::string& name, const std::string& where);

// The values a scene file's render block gives `method`: none unless the block names this method or
// none. Each value's origin ("SCENE: render.NAME") is appended to `origins`. Throws
// std::invalid_argument naming the origin for an option the method does not have, and for one that
// would choose where Lucent writes (a text option: dump): a scene file is data, perhaps downloaded,
// and where Lucent writes comes from whoever runs it (every front end: the command line, Python).
OptionValues sceneRenderBlockOptions(const Scene& scene, const Method& method, std::vector<std::string>& origins);

// Throws std::invalid_argument unless every directory the resolved options name for output (the
// dump directory) is free of the scene's files under a dump file's name (NAME.bin), which the
// dumps would replace: refused before any work, as an output path is.
void checkOutputDirectories(const Method& method, const OptionValues& resolved, const Scene& scene);

}  // namespace lucent
