# Writes the version header at build time (not only at configure time), so that summary.json names
# the commit that was built. Rewrites the file only when its content changes.
execute_process(COMMAND git describe --always --dirty --tags WORKING_DIRECTORY ${SOURCE_DIR}
                OUTPUT_VARIABLE git_version OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
if(NOT git_version)
  set(git_version "unknown")
endif()
set(content "// Generated at build time by cmake/version.cmake; do not edit.
#pragma once
namespace tessera {
inline constexpr const char* kTesseraVersion = \"${PROJECT_VERSION}+${git_version}\";
inline constexpr bool kFluidModule = ${FLUID_MODULE};
}  // namespace tessera
")
if(EXISTS ${OUTPUT})
  file(READ ${OUTPUT} old)
endif()
if(NOT "${old}" STREQUAL "${content}")
  file(WRITE ${OUTPUT} "${content}")
endif()
