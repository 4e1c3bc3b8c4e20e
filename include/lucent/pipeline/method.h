// A rendering method as the command line, scene files and other programs see it: a name, a line
// of summary, its declared options (pipeline/options.h), and a render call that takes option
// values by name over the defaults. `lucent/methods/methods.h` lists the methods.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "lucent/core/stop.h"
#include "lucent/pipeline/options.h"
#include "lucent/pipeline/render_control.h"
#include "lucent/pipeline/render_output.h"
#include "lucent/scene/scene.h"
#include "lucent/trace/visibility.h"

namespace lucent {

class Method {
 public:
  virtual ~Method() = default;
  virtual const std::string& name() const = 0;
  virtual const std::string& summary() const = 0;
  virtual const std::vector<OptionSpec>& options() const = 0;
  // Every option's value once `values` are set over the defaults, in declaration order, as text.
  // Throws OptionError for an unknown option or a value the option does not take.
  virtual OptionValues resolve(const OptionValues& values) const = 0;
  // Renders with `values` set over the defaults; throws OptionError as resolve does. A stop request
  // (control.stop) ends an interruptible method's sampling with what it has (complete false); one
  // before its sampling starts, or in any other method, throws RenderStopped (core/stop.h).
  virtual RenderOutput render(const Scene& scene, const Visibility& visibility, const OptionValues& values,
                              const RenderControl& control = {}) const = 0;
  // Whether the method honours RenderControl's checkpoints and resume, and returns the samples it
  // has when stopped (a method that does not refuses a control that asks for checkpoints or a
  // resume).
  virtual bool interruptible() const = 0;
};

// A method whose options are the struct Options, declared by `table`, rendered by `render`.
template <class Options>
class DeclaredMethod final : public Method {
 public:
  using RenderFn = RenderOutput (*)(const Scene&, const Visibility&, const Options&, const RenderControl&);
  DeclaredMethod(std::string name, std::string summary, const OptionTable<Options>& table, RenderFn render,
                 bool interruptible)
      : name_(std::move(name)), summary_(std::move(summary)), table_(table), render_(render),
        interruptible_(interruptible) {}
  const std::string& name() const override { return name_; }
  const std::string& summary() const override { return summary_; }
  const std::vector<OptionSpec>& options() const override { return table_.specs(); }
  OptionValues resolve(const OptionValues& values) const override { return table_.values(parse(values)); }
  RenderOutput render(const Scene& scene, const Visibility& visibility, const OptionValues& values,
                      const RenderControl& control) const override {
    const StopScope stops(control.stop);
    return render_(scene, visibility, parse(values), control);
  }
  bool interruptible() const override { return interruptible_; }

 private:
  Options parse(const OptionValues& values) const {
    Options options = table_.defaults();
    for (const auto& [name, text] : values) table_.set(options, name, text);
    table_.validate(options);
    return options;
  }
  std::string name_, summary_;
  const OptionTable<Options>& table_;
  RenderFn render_;
  bool interruptible_;
};

}  // namespace lucent
