// Strict access to a JSON object: every key read is marked used, typed getters name the key path in
// their errors, and finish() rejects the keys nobody read.
#pragma once
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "lucent/core/math.h"
#include "lucent/scene/loader.h"

namespace lucent::detail {

class JsonFields {
 public:
  JsonFields(const nlohmann::json& object, std::string file, std::string path)
      : object_(object), file_(std::move(file)), path_(std::move(path)) {
    if (!object_.is_object()) fail("expected an object");
  }

  [[noreturn]] void fail(const std::string& what) const {
    throw SceneError(file_ + ": " + (path_.empty() ? "top level" : path_) + ": " + what);
  }
  [[noreturn]] void failKey(const std::string& key, const std::string& what) const {
    throw SceneError(file_ + ": " + keyPath(key) + ": " + what);
  }
  std::string keyPath(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
  const std::string& file() const { return file_; }

  bool has(const std::string& key) const { return object_.contains(key); }
  const nlohmann::json& raw(const std::string& key) {
    if (!object_.contains(key)) failKey(key, "is required");
    used_.insert(key);
    return object_.at(key);
  }
  JsonFields object(const std::string& key) { return JsonFields(raw(key), file_, keyPath(key)); }

  float number(const std::string& key) {
    const auto& v = raw(key);
    if (!v.is_number()) failKey(key, "expected a number");
    const double f = v.get<double>();
    if (!std::isfinite(f) || std::abs(f) > kMaxInputMagnitude) failKey(key, "must be finite and at most 1e15 in magnitude");
    return float(f);
  }
  float number(const std::string& key, float fallback) { return has(key) ? number(key) : fallback; }
  bool boolean(const std::string& key) {
    const auto& v = raw(key);
    if (!v.is_boolean()) failKey(key, "expected true or false");
    return v.get<bool>();
  }
  std::string string(const std::string& key) {
    const auto& v = raw(key);
    if (!v.is_string()) failKey(key, "expected a string");
    return v.get<std::string>();
  }
  Vec3 vec3(const std::string& key) {
    const auto& v = raw(key);
    if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number())
      failKey(key, "expected an array of 3 numbers");
    for (int i = 0; i < 3; ++i) {
      const double f = v[i].get<double>();
      if (!std::isfinite(f) || std::abs(f) > kMaxInputMagnitude)
        failKey(key, "must be finite and at most 1e15 in magnitude");
    }
    return {v[0].get<float>(), v[1].get<float>(), v[2].get<float>()};
  }
  // Radiometric triple: finite and non-negative.
  Rgb rgb(const std::string& key) {
    const Vec3 v = vec3(key);
    if (v.x < 0 || v.y < 0 || v.z < 0) failKey(key, "must not be negative");
    return {v.x, v.y, v.z};
  }

  void finish() const {
    for (const auto& [key, value] : object_.items())
      if (!used_.count(key)) failKey(key, "unknown key");
  }

 private:
  const nlohmann::json& object_;
  std::string file_, path_;
  std::set<std::string> used_;
};

}  // namespace lucent::detail
