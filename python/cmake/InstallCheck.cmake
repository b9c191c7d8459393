# ctest's python_capecloth_install: installs the module alone (cmake --install --component python) under a
# fresh prefix in the build tree, into the same folder relative to the prefix as a real install, and imports
# it from there with the interpreter it was built for, PYTHONPATH set to that folder and nothing else.
# Variables: BUILD (the build tree), PREFIX (a scratch prefix), DIR (the folder relative to the prefix),
# PYTHON (the interpreter).
file(REMOVE_RECURSE ${PREFIX})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD} --component python --prefix ${PREFIX}
  RESULT_VARIABLE installed)
if(NOT installed EQUAL 0)
  message(FATAL_ERROR "cmake --install --component python failed")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} -E env PYTHONPATH=${PREFIX}/${DIR}
  ${PYTHON} -c "import capecloth, sys; print(capecloth.__file__, capecloth.__version__); sys.exit(not capecloth.__file__.startswith('${PREFIX}/${DIR}/'))"
  WORKING_DIRECTORY ${PREFIX} RESULT_VARIABLE imported)
if(NOT imported EQUAL 0)
  message(FATAL_ERROR "the installed module does not import from ${PREFIX}/${DIR}")
endif()
file(REMOVE_RECURSE ${PREFIX})
