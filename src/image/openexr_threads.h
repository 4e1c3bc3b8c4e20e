// liblucent_image_exr.so's thread count for one file, from the caller's bound (--threads).
#pragma once
#include <OpenEXR/ImfThreading.h>

#include <algorithm>
#include <mutex>
#include <thread>

namespace lucent {

// OpenEXR's pool is started once, with a thread per core; a file given n threads keeps 2n line
// buffers in flight, as many pool threads busy at most: n is half of `threads`, so that --threads
// bounds the reading and writing too. 0 (the calling thread alone) where `threads` is 1.
inline int openexrThreads(int threads) {
  if (threads < 2) return 0;
  static std::once_flag pool;
  std::call_once(pool, [] { Imf::setGlobalThreadCount(int(std::max(1u, std::thread::hardware_concurrency()))); });
  return std::min(threads / 2, Imf::globalThreadCount());
}

}  // namespace lucent
