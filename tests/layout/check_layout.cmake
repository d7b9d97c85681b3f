# The layout check: every folder of base/, tracking/ and engine/ is one target, and its code
# includes only what the "may include" column of its README's table allows.
#
#   cmake -DSOURCE_DIR=<repo> [-DPRETEND_FILE=<file> -DPRETEND_PATH=<repo path>] -P check_layout.cmake
#
# The tables are the rows of base/README.md, tracking/README.md and engine/README.md that start
# with a folder in backticks ("| `engine/core/` | ..."); the last column names, in backticks, the
# folders that folder's code may include. base/ may be included by every folder. A file belongs
# to the longest listed folder its path starts with (engine/render/vk/ is engine/render's). Also
# refused, with a message of its own: a runtime library including simulation code (tracking/sim,
# engine/sim), and a file under base/, tracking/ or engine/ in no listed folder. Includes are read
# in both forms, "..." and <...>.
#
# PRETEND_FILE is checked as if it were at PRETEND_PATH (the layout tests feed it bad includes to
# show that the check fails).
if(NOT SOURCE_DIR)
  message(FATAL_ERROR "check_layout: pass -DSOURCE_DIR=<the repository>")
endif()

set(folders "")
foreach(readme base/README.md tracking/README.md engine/README.md)
  if(NOT EXISTS "${SOURCE_DIR}/${readme}")
    message(FATAL_ERROR "check_layout: ${readme} is missing")
  endif()
  file(STRINGS "${SOURCE_DIR}/${readme}" rows REGEX "^\\| `[a-z/]+/` \\|")
  foreach(row IN LISTS rows)
    string(REGEX MATCH "^\\| `([a-z/]+)/`" _ "${row}")
    set(folder "${CMAKE_MATCH_1}")
    string(REGEX REPLACE "^.*\\|([^|]*)\\|[ \t]*$" "\\1" may "${row}")
    string(REGEX MATCHALL "`[a-z/]+`" allowed "${may}")
    list(TRANSFORM allowed REPLACE "`" "")
    list(TRANSFORM allowed REPLACE "/$" "")
    list(REMOVE_ITEM allowed "base")
    list(APPEND folders "${folder}")
    set(allowed_${folder} "${allowed}")
  endforeach()
endforeach()
if(NOT folders)
  message(FATAL_ERROR "check_layout: no folder rows found in the READMEs' tables")
endif()

# The listed folder a repository path belongs to ("" for none): the longest listed prefix.
function(owner path out)
  set(best "")
  foreach(f IN LISTS folders)
    string(LENGTH "${f}" n)
    string(LENGTH "${best}" nb)
    if(path MATCHES "^${f}/" AND n GREATER nb)
      set(best "${f}")
    endif()
  endforeach()
  set(${out} "${best}" PARENT_SCOPE)
endfunction()

set(problems "")
file(GLOB_RECURSE code RELATIVE "${SOURCE_DIR}" "${SOURCE_DIR}/base/*.h" "${SOURCE_DIR}/base/*.cpp" "${SOURCE_DIR}/tracking/*.h"
     "${SOURCE_DIR}/tracking/*.cpp" "${SOURCE_DIR}/engine/*.h" "${SOURCE_DIR}/engine/*.cpp")
set(checked "")
foreach(f IN LISTS code)
  list(APPEND checked "${f}|${SOURCE_DIR}/${f}")
endforeach()
if(PRETEND_FILE)
  list(APPEND checked "${PRETEND_PATH}|${PRETEND_FILE}")
endif()

foreach(entry IN LISTS checked)
  string(REPLACE "|" ";" parts "${entry}")
  list(GET parts 0 path)
  list(GET parts 1 file)
  owner("${path}" from)
  if(NOT from)
    get_filename_component(dir "${path}" DIRECTORY)
    list(APPEND problems "${path}: its folder ${dir}/ has no row in its README's table")
    continue()
  endif()
  file(STRINGS "${file}" includes REGEX "^[ \t]*#[ \t]*include[ \t]*[\"<](base|tracking|engine|tools|tests)/")
  foreach(line IN LISTS includes)
    string(REGEX MATCH "[\"<]([^\">]+)[\">]" _ "${line}")
    set(target "${CMAKE_MATCH_1}")
    owner("${target}" to)
    if(to STREQUAL from OR to STREQUAL "base")
      continue()
    endif()
    if(target MATCHES "^(tracking|engine)/sim/" AND NOT from MATCHES "^(tracking|engine)/sim$")
      list(APPEND problems "${path} includes ${target}: ${from} is a runtime library and may not include simulation code")
      continue()
    endif()
    if(NOT to)
      list(APPEND problems "${path} includes ${target}, which is in no listed folder")
      continue()
    endif()
    list(FIND allowed_${from} "${to}" at)
    if(at EQUAL -1)
      set(may base ${allowed_${from}})
      string(REPLACE ";" ", " may "${may}")
      list(APPEND problems "${path} includes ${target}: ${from} may include only ${may} (its README's table)")
    endif()
  endforeach()
endforeach()

# tracking/ is a library of its own: its CMakeLists may not name an engine target either.
file(STRINGS "${SOURCE_DIR}/tracking/CMakeLists.txt" engine_links REGEX "rhot_engine|rhot::engine")
if(engine_links)
  list(APPEND problems "tracking/CMakeLists.txt links engine/: ${engine_links}")
endif()

if(problems)
  list(JOIN problems "\n  " text)
  message(FATAL_ERROR "layout check failed:\n  ${text}")
endif()
list(LENGTH checked n)
list(LENGTH folders nf)
message(STATUS "layout check: ${n} files in ${nf} folders include only what their READMEs allow")
