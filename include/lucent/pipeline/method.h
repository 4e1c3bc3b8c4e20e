// A rendering method as the command line, scene files and other programs see it: a name, a line
// of summary, its declared options (pipeline/options.h), the resolution of option values given by
// name into the method's typed options, and a render call that takes them. `lucent/methods/methods.h`
// lists the methods; a program that knows its method calls the typed renderX functions instead.
#pragma once
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "lucent/core/stop.h"
#include "lucent/pipeline/dump_settings.h"
#include "lucent/pipeline/options.h"
#include "lucent/pipeline/render_options.h"
#include "lucent/pipeline/render_control.h"
#include "lucent/pipeline/render_output.h"
#include "lucent/scene/scene.h"
#include "lucent/trace/visibility.h"

namespace lucent {

// What of KHR_materials_transmission's light a method renders: some of it (the point-based
// methods take the diffuse part of rough transmitters, and follow smooth ones as glass, as every
// method's camera paths do), or all of it, with a KHR_materials_volume medium's attenuation.
enum class TransmissionRendered { InPart, All };

// A method's options, set from values by name over its defaults and checked: the method's typed
// options struct inside (Method::resolve).
class MethodOptions {
 public:
  virtual ~MethodOptions() = default;
  virtual const CommonOptions& common() const = 0;
  // Every option's value as text, in declaration order (the JSON echo and the EXR metadata).
  virtual OptionValues values() const = 0;
};

class Method {
 public:
  virtual ~Method() = default;
  virtual const std::string& name() const = 0;
  virtual const std::string& summary() const = 0;
  virtual const std::vector<OptionSpec>& options() const = 0;
  // The method's options with `values` set over its defaults, parsed and checked once. Throws
  // OptionError for an unknown option, a value the option does not take, or a broken rule.
  virtual std::unique_ptr<MethodOptions> resolve(const OptionValues& values) const = 0;
  // Renders with options this method resolved (std::invalid_argument for another method's). A stop
  // request (control.stop) ends an interruptible method's sampling with what it has (complete
  // false); one before its sampling starts, or in any other method, throws RenderStopped
  // (core/stop.h).
  virtual RenderOutput render(const Scene& scene, const Visibility& visibility, const MethodOptions& options,
                              const RenderControl& control = {}) const = 0;
  // Resolves `values` and renders with them.
  RenderOutput render(const Scene& scene, const Visibility& visibility, const OptionValues& values,
                      const RenderControl& control = {}) const {
    return render(scene, visibility, *resolve(values), control);
  }
  // Whether the method honours RenderControl's checkpoints and resume, and returns the samples it
  // has when stopped (a method that does not refuses a control that asks for checkpoints or a
  // resume).
  virtual bool interruptible() const = 0;
  // What of the light glTF materials pass through surfaces it renders (a render lists what it leaves
  // out).
  virtual TransmissionRendered rendersTransmission() const = 0;
};

// A method whose options are the struct Options, declared by `table`, rendered by `render`.
template <class Options>
class DeclaredMethod final : public Method {
 public:
  using RenderFn = RenderOutput (*)(const Scene&, const Visibility&, const Options&, const RenderControl&);
  DeclaredMethod(std::string name, std::string summary, const OptionTable<Options>& table, RenderFn render,
                 bool interruptible, TransmissionRendered rendersTransmission)
      : name_(std::move(name)), summary_(std::move(summary)), table_(table), render_(render),
        interruptible_(interruptible), rendersTransmission_(rendersTransmission) {}
  const std::string& name() const override { return name_; }
  const std::string& summary() const override { return summary_; }
  const std::vector<OptionSpec>& options() const override { return table_.specs(); }
  std::unique_ptr<MethodOptions> resolve(const OptionValues& values) const override {
    auto resolved = std::make_unique<Resolved>(table_);
    for (const auto& [name, text] : values) table_.set(resolved->options, name, text);
    table_.setConditionalDefaults(resolved->options, values);
    table_.validate(resolved->options);
    return resolved;
  }
  RenderOutput render(const Scene& scene, const Visibility& visibility, const MethodOptions& options,
                      const RenderControl& control) const override {
    const auto* resolved = dynamic_cast<const Resolved*>(&options);
    if (!resolved || &resolved->table != &table_)
      throw std::invalid_argument("--method " + name_ + " was given another method's options");
    const StopScope stops(control.stop);
    RenderOutput out = render_(scene, visibility, resolved->options, control);
    // A render that dumps its stages says beside the arrays what they were made with.
    const OptionValues values = table_.values(resolved->options);
    for (const auto& [name, value] : values)
      if (name == "dump" && !value.empty()) writeDumpSettings(value, name_, optionsJsonText(table_.specs(), values), out.stats, scene);
    return out;
  }
  using Method::render;
  bool interruptible() const override { return interruptible_; }
  TransmissionRendered rendersTransmission() const override { return rendersTransmission_; }

 private:
  struct Resolved final : MethodOptions {
    explicit Resolved(const OptionTable<Options>& t) : table(t), options(t.defaults()) {}
    const CommonOptions& common() const override { return options.common; }
    OptionValues values() const override { return table.values(options); }
    const OptionTable<Options>& table;
    Options options;
  };
  std::string name_, summary_;
  const OptionTable<Options>& table_;
  RenderFn render_;
  bool interruptible_;
  TransmissionRendered rendersTransmission_;
};

}  // namespace lucent
