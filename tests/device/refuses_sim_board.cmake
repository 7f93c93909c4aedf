# The device binary built without the virtual scanner (FPP_SCANNER_SIM OFF,
# preset aarch64, where the arm64 binary runs under qemu-user through
# binfmt_misc like every program a test starts) must refuse a board file
# with a sim section at start: exit status 1, one error line naming the board
# file and saying the binary has no virtual scanner, nothing written.
# Usage (tests/CMakeLists.txt): cmake -DSCANNER=EXE -DBOARD=FILE -DSTORE=DIR -P refuses_sim_board.cmake
foreach(var SCANNER BOARD STORE)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "refuses_sim_board: -D${var}=... missing")
  endif()
endforeach()
file(REMOVE_RECURSE ${STORE})
unset(ENV{JOURNAL_STREAM}) # "error: " prefixes, not the journal's
execute_process(COMMAND ${SCANNER} --board ${BOARD} --once --mode capture --store ${STORE}/scans
                RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 100)
message(STATUS "exit status ${status}; stderr: ${err}")
if(NOT status STREQUAL "1")
  message(FATAL_ERROR "${SCANNER} on ${BOARD}: exit status ${status}, not 1")
endif()
set(expected "error: ${BOARD}: sim: this fpp-scanner was built without the virtual scanner")
string(FIND "${err}" "${expected}" at)
if(NOT at EQUAL 0)
  message(FATAL_ERROR "stderr does not start with '${expected}'")
endif()
string(REGEX MATCHALL "\n" lines "${err}")
list(LENGTH lines count)
if(NOT count EQUAL 1 OR NOT out STREQUAL "")
  message(FATAL_ERROR "one error line and no output expected; stdout: '${out}'")
endif()
if(EXISTS ${STORE})
  message(FATAL_ERROR "the refused board left ${STORE}")
endif()
