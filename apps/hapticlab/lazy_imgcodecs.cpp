// OpenCV's image reading and writing, loaded on first use (the hapticlab binary only).
//
// libopencv_imgcodecs depends on GDAL, Poppler, HDF5, libheif, MariaDB's client and about
// 150 other shared libraries; loading and relocating them took 0.06 s of the 0.087 s of CPU
// that `hapticlab --help` spent before this file (docs/performance.md, "Start-up"). Only
// a few commands read or write images (model photometric, the screenshots of the participant
// window). This file defines the functions of imgcodecs that the project calls, cv::imread,
// cv::imwrite and cv::haveImageReader, in the executable itself: the linker resolves the calls in
// the libraries (modeling, runner_ui) and the commands to these definitions, and --as-needed
// (apps/hapticlab/CMakeLists.txt) leaves libopencv_imgcodecs off the binary's start-up. Each
// definition opens the library with dlopen at its first call and forwards to its function.
//
// The library's functions are found by their mangled names (the Itanium C++ ABI of g++ and
// clang with libstdc++'s std::string); a name that is missing (another OpenCV ABI) is an
// environment failure with a sentence, and the photometric command-line tests read and write
// images through this path. The tests link libopencv_imgcodecs directly, as before. A call of
// another imgcodecs function would put the library back into the start-up (the linker keeps
// it for that symbol): Cli.ImageCodecsAreNotLoadedAtStartUp notices; add the function here.
//
// Hand-written: glibc's linker has no delay-loading of a DT_NEEDED library, and OpenCV has
// no plugin interface for its codecs.

#include <dlfcn.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#ifndef HL_OPENCV_IMGCODECS_PATH
#error "HL_OPENCV_IMGCODECS_PATH (the path of libopencv_imgcodecs) must be defined"
#endif

namespace {

void* Codecs() {
  static void* handle = dlopen(HL_OPENCV_IMGCODECS_PATH, RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr) {
    const char* why = dlerror();
    throw std::runtime_error(std::string("cannot load OpenCV's image codecs (") +
                             HL_OPENCV_IMGCODECS_PATH + "): " + (why ? why : "unknown error"));
  }
  return handle;
}

void* Symbol(const char* mangled, const char* name) {
  void* f = dlsym(Codecs(), mangled);
  if (f == nullptr) {
    throw std::runtime_error(std::string("OpenCV's image codecs (") + HL_OPENCV_IMGCODECS_PATH +
                             ") have no " + name + " of the expected signature");
  }
  return f;
}

using ImreadFn = cv::Mat (*)(const cv::String&, int);
using ImwriteFn = bool (*)(const cv::String&, cv::InputArray, const std::vector<int>&);
using HaveReaderFn = bool (*)(const cv::String&);

}  // namespace

namespace cv {

Mat imread(const String& filename, int flags) {
  static auto* f = reinterpret_cast<ImreadFn>(
      Symbol("_ZN2cv6imreadERKNSt7__cxx1112basic_stringIcSt11char_traitsIcESaIcEEEi", "imread"));
  return f(filename, flags);
}

bool imwrite(const String& filename, InputArray img, const std::vector<int>& params) {
  static auto* f = reinterpret_cast<ImwriteFn>(
      Symbol("_ZN2cv7imwriteERKNSt7__cxx1112basic_stringIcSt11char_traitsIcESaIcEEERKNS_"
             "11_InputArrayERKSt6vectorIiSaIiEE",
             "imwrite"));
  return f(filename, img, params);
}

bool haveImageReader(const String& filename) {
  static auto* f = reinterpret_cast<HaveReaderFn>(
      Symbol("_ZN2cv15haveImageReaderERKNSt7__cxx1112basic_stringIcSt11char_traitsIcESaIcEEE",
             "haveImageReader"));
  return f(filename);
}

}  // namespace cv
