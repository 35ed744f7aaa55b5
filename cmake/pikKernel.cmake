# pik_add_kernel(<target> <file.pik>
#                [TARGET reference|avx2|avx512|sve|auto] [NAME Class]
#                [EPI Type] [EPJ Type] [FORCE Type]
#                [HEADER particle.hpp] [OUTPUT file.hpp] [OPTIONS extra pikg-gen options...])
#
# Runs pikg-gen at build time (again whenever the .pik file or pikg-gen changes)
# and makes the generated header includable from <target> as "<OUTPUT>"
# (default: "<NAME or file stem>.hpp"). With HEADER, the target's include
# directories and compile definitions are passed on to pikg-reflect.
include_guard(GLOBAL)

function(pik_add_kernel target pik_file)
  cmake_parse_arguments(PARSE_ARGV 2 K "" "TARGET;NAME;EPI;EPJ;FORCE;HEADER;OUTPUT" "OPTIONS")
  if(K_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "pik_add_kernel(${target} ${pik_file}): unknown arguments: ${K_UNPARSED_ARGUMENTS}")
  endif()
  if(NOT PIKG_GEN_EXECUTABLE)
    message(FATAL_ERROR "pik_add_kernel: PIKG_GEN_EXECUTABLE is not set (use find_package(pik))")
  endif()
  get_filename_component(pik_abs "${pik_file}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_SOURCE_DIR}")
  if(NOT EXISTS "${pik_abs}")
    message(FATAL_ERROR "pik_add_kernel(${target}): no such kernel file: ${pik_abs}")
  endif()
  get_filename_component(stem "${pik_abs}" NAME_WE)
  if(NOT K_TARGET)
    set(K_TARGET auto)
  endif()
  if(K_OUTPUT)
    set(out_name "${K_OUTPUT}")
  elseif(K_NAME)
    string(REPLACE "::" "_" out_name "${K_NAME}")
    set(out_name "${out_name}.hpp")
  else()
    set(out_name "${stem}.hpp")
  endif()
  set(out_dir "${CMAKE_CURRENT_BINARY_DIR}/pik_kernels/${target}")
  set(out "${out_dir}/${out_name}")

  set(args "${pik_abs}" -o "${out}" --target "${K_TARGET}")
  if(K_NAME)
    list(APPEND args --name "${K_NAME}")
  endif()
  foreach(role EPI EPJ FORCE)
    if(K_${role})
      string(TOLOWER ${role} opt)
      list(APPEND args --${opt} "${K_${role}}")
    endif()
  endforeach()
  if(K_HEADER)
    get_filename_component(hdr_abs "${K_HEADER}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_SOURCE_DIR}")
    list(APPEND args --header "${hdr_abs}")
    set(incs "$<TARGET_PROPERTY:${target},INCLUDE_DIRECTORIES>")
    set(defs "$<TARGET_PROPERTY:${target},COMPILE_DEFINITIONS>")
    # $<SEMICOLON>: a literal ';' here would split the generator expression itself;
    # COMMAND_EXPAND_LISTS turns the evaluated list into one argument per item.
    list(APPEND args "$<$<BOOL:${incs}>:-I$<JOIN:${incs},$<SEMICOLON>-I>>"
                     "$<$<BOOL:${defs}>:-D$<JOIN:${defs},$<SEMICOLON>-D>>")
    set(hdr_dep "${hdr_abs}")
    # Inside the pik build, pikg-reflect must exist before the kernel is generated.
    if(TARGET pikg-reflect)
      list(APPEND hdr_dep pikg-reflect)
    endif()
  endif()
  list(APPEND args ${K_OPTIONS})

  file(GLOB_RECURSE gen_sources CONFIGURE_DEPENDS
       "${PIK_COMPILER_DIR}/pik_gen/*.py" "${PIK_COMPILER_DIR}/pik_gen/*.j2")
  file(RELATIVE_PATH rel_out "${CMAKE_BINARY_DIR}" "${out}")
  add_custom_command(
    OUTPUT "${out}"
    COMMAND "${PIKG_GEN_EXECUTABLE}" ${args}
    DEPENDS "${pik_abs}" ${hdr_dep} ${gen_sources} "${PIKG_GEN_EXECUTABLE}"
    COMMENT "pikg-gen ${pik_file} -> ${rel_out} (${K_TARGET})"
    COMMAND_EXPAND_LISTS VERBATIM)
  target_sources(${target} PRIVATE "${out}")
  target_include_directories(${target} PRIVATE "${out_dir}")
endfunction()
