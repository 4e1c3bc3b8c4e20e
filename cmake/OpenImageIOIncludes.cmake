# Debian's OpenImageIO config lists /usr/include/opencv4 among its include directories, which
# exists only with OpenCV installed; CMake refuses an imported target with a missing include path.
if(TARGET OpenImageIO::OpenImageIO)
  get_target_property(_lucent_oiio_includes OpenImageIO::OpenImageIO INTERFACE_INCLUDE_DIRECTORIES)
  list(FILTER _lucent_oiio_includes EXCLUDE REGEX "opencv")
  set_target_properties(OpenImageIO::OpenImageIO PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${_lucent_oiio_includes}")
  unset(_lucent_oiio_includes)
endif()
