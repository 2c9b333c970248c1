# Copies the shared libraries MODULE needs into DEST, except those every Linux system has (the C library, the
# dynamic loader, libm, libgcc_s, libstdc++): the FMU carries them (RPATH $ORIGIN).
file(GET_RUNTIME_DEPENDENCIES LIBRARIES ${MODULE} RESOLVED_DEPENDENCIES_VAR _deps UNRESOLVED_DEPENDENCIES_VAR _missing
     PRE_EXCLUDE_REGEXES "^ld-linux" "^libc\\.so" "^libm\\.so" "^libgcc_s\\.so" "^libstdc\\+\\+\\.so" "^libpthread\\.so"
                         "^libdl\\.so" "^librt\\.so" "^linux-vdso")
if(_missing)
  message(FATAL_ERROR "jointsim_fmu: unresolved libraries: ${_missing}")
endif()
foreach(_lib ${_deps})
  get_filename_component(_real ${_lib} REALPATH)
  get_filename_component(_name ${_lib} NAME)
  # Copied under the name the loader looks for (the soname the module or a carried library records).
  configure_file(${_real} ${DEST}/${_name} COPYONLY)
endforeach()
