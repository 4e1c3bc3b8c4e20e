#include "opencl_device.h"

#include <stdexcept>
#include <type_traits>

namespace lucent::opencl {

void check(cl_int status, const char* what) {
  if (status != CL_SUCCESS) throw std::runtime_error(std::string(what) + " failed with OpenCL error " + std::to_string(status));
}

namespace {

// A string property of a platform or device (clGetPlatformInfo, clGetDeviceInfo), without its NUL.
template <class Object, class Info>
std::string infoString(cl_int (*get)(Object, Info, size_t, void*, size_t*), Object object, std::type_identity_t<Info> what) {
  size_t n = 0;
  check(get(object, what, 0, nullptr, &n), "clGet*Info");
  std::string s(n, '\0');
  check(get(object, what, n, s.data(), nullptr), "clGet*Info");
  while (!s.empty() && s.back() == '\0') s.pop_back();
  return s;
}

}  // namespace

Device::Device(const std::string& wanted) {
  cl_uint platformCount = 0;
  if (clGetPlatformIDs(0, nullptr, &platformCount) != CL_SUCCESS || platformCount == 0)
    throw std::runtime_error("no OpenCL platform: install an OpenCL driver (Debian: pocl-opencl-icd)");
  std::vector<cl_platform_id> platforms(platformCount);
  check(clGetPlatformIDs(platformCount, platforms.data(), nullptr), "clGetPlatformIDs");
  struct Candidate {
    cl_platform_id platform;
    cl_device_id device;
    bool gpu;
  };
  std::vector<Candidate> candidates;
  std::string seen;
  for (cl_platform_id p : platforms) {
    cl_uint n = 0;
    if (clGetDeviceIDs(p, CL_DEVICE_TYPE_ALL, 0, nullptr, &n) != CL_SUCCESS || n == 0) continue;
    std::vector<cl_device_id> devices(n);
    check(clGetDeviceIDs(p, CL_DEVICE_TYPE_ALL, n, devices.data(), nullptr), "clGetDeviceIDs");
    for (cl_device_id d : devices) {
      cl_device_type type = 0;
      check(clGetDeviceInfo(d, CL_DEVICE_TYPE, sizeof type, &type, nullptr), "clGetDeviceInfo");
      const std::string name = infoString(clGetDeviceInfo, d, CL_DEVICE_NAME);
      seen += (seen.empty() ? "" : ", ") + name;
      if (wanted.empty() || name.find(wanted) != std::string::npos) candidates.push_back({p, d, (type & CL_DEVICE_TYPE_GPU) != 0});
    }
  }
  if (candidates.empty())
    throw std::runtime_error(wanted.empty() ? "no OpenCL device"
                                            : "no OpenCL device named like '" + wanted + "' (there are: " + seen + ")");
  Candidate chosen = candidates.front();
  for (const Candidate& c : candidates)
    if (c.gpu) {
      chosen = c;
      break;
    }
  device_ = chosen.device;
  name_ = infoString(clGetDeviceInfo, device_, CL_DEVICE_NAME);
  platform_ = infoString(clGetPlatformInfo, chosen.platform, CL_PLATFORM_NAME);
  cl_int status = CL_SUCCESS;
  context_ = clCreateContext(nullptr, 1, &device_, nullptr, nullptr, &status);
  check(status, "clCreateContext");
  queue_ = clCreateCommandQueue(context_, device_, 0, &status);
  if (status != CL_SUCCESS) clReleaseContext(context_);  // the destructor does not run for a throwing constructor
  check(status, "clCreateCommandQueue");
}

Device::~Device() {
  if (queue_) clReleaseCommandQueue(queue_);
  if (context_) clReleaseContext(context_);
}

Program Device::build(const std::vector<std::string>& sources) const {
  std::vector<std::string> texts;
  for (const std::string& s : sources) {
    const std::string_view file = kernelSource(s);
    texts.emplace_back(file.empty() ? s : std::string(file));
    texts.back() += "\n";
  }
  std::vector<const char*> pointers;
  for (const std::string& t : texts) pointers.push_back(t.c_str());
  cl_int status = CL_SUCCESS;
  Program program(clCreateProgramWithSource(context_, cl_uint(pointers.size()), pointers.data(), nullptr, &status));
  check(status, "clCreateProgramWithSource");
  // Division and square root rounded as the C++ build rounds them, where the device can: the kernels'
  // yes-or-no tests (a photon's side, a cache within its radius) would otherwise differ by an ulp.
  cl_device_fp_config fp = 0;
  check(clGetDeviceInfo(device_, CL_DEVICE_SINGLE_FP_CONFIG, sizeof fp, &fp, nullptr), "clGetDeviceInfo");
  const char* options = (fp & CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT) ? "-cl-std=CL1.2 -cl-fp32-correctly-rounded-divide-sqrt"
                                                                  : "-cl-std=CL1.2";
  status = clBuildProgram(program.get(), 1, &device_, options, nullptr, nullptr);
  if (status != CL_SUCCESS) {
    size_t n = 0;
    clGetProgramBuildInfo(program.get(), device_, CL_PROGRAM_BUILD_LOG, 0, nullptr, &n);
    std::string log(n, '\0');
    clGetProgramBuildInfo(program.get(), device_, CL_PROGRAM_BUILD_LOG, n, log.data(), nullptr);
    throw std::runtime_error("OpenCL build failed on " + name_ + " (error " + std::to_string(status) + "):\n" + log);
  }
  return program;
}

Kernel Device::kernel(const Program& program, const char* name) const {
  cl_int status = CL_SUCCESS;
  Kernel k(clCreateKernel(program.get(), name, &status));
  check(status, (std::string("clCreateKernel ") + name).c_str());
  return k;
}

Buffer Device::input(const void* data, size_t bytes) const {
  cl_int status = CL_SUCCESS;
  static const char kOneByte = 0;
  Buffer b(clCreateBuffer(context_, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, bytes > 0 ? bytes : 1,
                          const_cast<void*>(bytes > 0 ? data : &kOneByte), &status));
  check(status, "clCreateBuffer");
  return b;
}

Buffer Device::output(size_t bytes) const {
  cl_int status = CL_SUCCESS;
  Buffer b(clCreateBuffer(context_, CL_MEM_READ_WRITE, bytes > 0 ? bytes : 1, nullptr, &status));
  check(status, "clCreateBuffer");
  return b;
}

void Device::read(const Buffer& buffer, void* data, size_t bytes) const {
  if (bytes == 0) return;
  check(clEnqueueReadBuffer(queue_, buffer.get(), CL_TRUE, 0, bytes, data, 0, nullptr, nullptr), "clEnqueueReadBuffer");
}

void Device::run(const Kernel& kernel, size_t items) const {
  if (items == 0) return;
  check(clEnqueueNDRangeKernel(queue_, kernel.get(), 1, nullptr, &items, nullptr, 0, nullptr, nullptr),
        "clEnqueueNDRangeKernel");
  check(clFinish(queue_), "clFinish");
}

void setArg(const Kernel& kernel, cl_uint index, const Buffer& buffer) {
  const cl_mem m = buffer.get();
  check(clSetKernelArg(kernel.get(), index, sizeof m, &m), "clSetKernelArg");
}

}  // namespace lucent::opencl
