// A minimal OpenCL host: one device, its context and queue, programs built from Lucent's kernel
// sources (compiled into the binary from backends/opencl/kernels), buffers and launches. Errors
// throw std::runtime_error with the call, the OpenCL error code and, for a failed build, the log.
#pragma once
#define CL_TARGET_OPENCL_VERSION 120
#include <CL/cl.h>

#include <cstddef>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace lucent::opencl {

// The text of a kernel source file of backends/opencl/kernels ("records.cl", "knn_grid.cl", ...).
std::string_view kernelSource(std::string_view file);

// Throws std::runtime_error naming `what` unless `status` is CL_SUCCESS.
void check(cl_int status, const char* what);

struct ReleaseMem { void operator()(cl_mem m) const { clReleaseMemObject(m); } };
struct ReleaseKernel { void operator()(cl_kernel k) const { clReleaseKernel(k); } };
struct ReleaseProgram { void operator()(cl_program p) const { clReleaseProgram(p); } };
using Buffer = std::unique_ptr<std::remove_pointer_t<cl_mem>, ReleaseMem>;
using Kernel = std::unique_ptr<std::remove_pointer_t<cl_kernel>, ReleaseKernel>;
using Program = std::unique_ptr<std::remove_pointer_t<cl_program>, ReleaseProgram>;

class Device {
 public:
  // The device whose name contains `wanted`; with "" the first GPU of any platform, else the first
  // device. Throws when there is no OpenCL platform or no such device (never a silent fallback).
  explicit Device(const std::string& wanted = "");
  ~Device();
  Device(const Device&) = delete;
  Device& operator=(const Device&) = delete;

  const std::string& name() const { return name_; }
  const std::string& platform() const { return platform_; }

  // A program from the named kernel files (each looked up with kernelSource) or literal sources,
  // concatenated in order; built with -cl-std=CL1.2.
  Program build(const std::vector<std::string>& sources) const;
  Kernel kernel(const Program& program, const char* name) const;

  // A read-only buffer holding `bytes` bytes (at least one byte is allocated: OpenCL refuses 0).
  Buffer input(const void* data, size_t bytes) const;
  template <class T>
  Buffer input(const std::vector<T>& data) const { return input(data.data(), data.size() * sizeof(T)); }
  Buffer output(size_t bytes) const;
  void read(const Buffer& buffer, void* data, size_t bytes) const;
  template <class T>
  std::vector<T> read(const Buffer& buffer, size_t count) const {
    std::vector<T> v(count);
    read(buffer, v.data(), count * sizeof(T));
    return v;
  }
  // Runs `items` work items of the kernel and waits for them.
  void run(const Kernel& kernel, size_t items) const;

 private:
  cl_device_id device_ = nullptr;
  cl_context context_ = nullptr;
  cl_command_queue queue_ = nullptr;
  std::string name_, platform_;
};

// Sets argument `index` of the kernel: a buffer, or a scalar passed by value.
void setArg(const Kernel& kernel, cl_uint index, const Buffer& buffer);
template <class T>
void setArg(const Kernel& kernel, cl_uint index, T value) {
  static_assert(std::is_arithmetic_v<T>);
  check(clSetKernelArg(kernel.get(), index, sizeof(T), &value), "clSetKernelArg");
}
template <class... Args>
void setArgs(const Kernel& kernel, const Args&... args) {
  cl_uint index = 0;
  (setArg(kernel, index++, args), ...);
}

}  // namespace lucent::opencl
