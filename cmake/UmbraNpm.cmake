# umbra_npm_ci(SOURCE_DIR DEST_DIR RESULT_VAR): installs the npm packages
# that SOURCE_DIR/package-lock.json pins into DEST_DIR/node_modules, at
# configure time with `npm ci --ignore-scripts` (again only when the lock file
# changes). Sets RESULT_VAR to TRUE when they are there, or to FALSE with a
# message saying why (npm missing, no network): umbra then builds without
# what needs them. The packages stay in the build folder, never in the
# source tree.
function(umbra_npm_ci source_dir dest_dir result_var)
  set(${result_var} FALSE PARENT_SCOPE)
  set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS
    ${source_dir}/package.json ${source_dir}/package-lock.json)
  find_program(UMBRA_NPM_EXECUTABLE npm)
  if(NOT UMBRA_NPM_EXECUTABLE)
    message(STATUS "umbra: npm not found: skipping the npm packages of ${source_dir} (Debian: apt-get install nodejs npm)")
    return()
  endif()
  file(SHA256 ${source_dir}/package-lock.json lock_hash)
  set(stamp ${dest_dir}/umbra-npm-ci.stamp)
  if(EXISTS ${stamp})
    file(READ ${stamp} installed_hash)
    if(installed_hash STREQUAL lock_hash AND EXISTS ${dest_dir}/node_modules)
      set(${result_var} TRUE PARENT_SCOPE)
      return()
    endif()
  endif()
  file(MAKE_DIRECTORY ${dest_dir})
  file(COPY ${source_dir}/package.json ${source_dir}/package-lock.json ${source_dir}/.npmrc DESTINATION ${dest_dir})
  message(STATUS "umbra: npm ci in ${dest_dir}")
  execute_process(
    COMMAND ${UMBRA_NPM_EXECUTABLE} ci --ignore-scripts --no-audit --no-fund --loglevel=error
    WORKING_DIRECTORY ${dest_dir}
    RESULT_VARIABLE npm_result
    OUTPUT_VARIABLE npm_output
    ERROR_VARIABLE npm_output)
  if(NOT npm_result EQUAL 0)
    message(WARNING "umbra: `npm ci` failed in ${dest_dir} (exit ${npm_result}); building without what needs it:\n${npm_output}")
    return()
  endif()
  file(WRITE ${stamp} ${lock_hash})
  set(${result_var} TRUE PARENT_SCOPE)
endfunction()
