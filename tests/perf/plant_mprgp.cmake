# Writes OUTPUT: a copy of SOURCE (solvers/mprgp/mprgp_decoupled_steps.cpp) with the planted regressions of PLANT
# (tests/perf/mprgp_plant.inc) hooked into the CG step's A-product (product_dot). Run with
#   cmake -DSOURCE=... -DPLANT=... -DOUTPUT=... -P plant_mprgp.cmake
# Fails when the anchors are gone, so a refactored source cannot silently lose the plants.
file(READ "${SOURCE}" text)
string(FIND "${text}" "namespace cb {" at_namespace)
if(at_namespace EQUAL -1)
  message(FATAL_ERROR "plant_mprgp: no 'namespace cb {' in ${SOURCE}")
endif()
set(product_regex "double (DecoupledMprgp::)?product_dot\\([^)]*\\)[ \t\r\n]*{")
string(REGEX MATCH "${product_regex}" anchor "${text}")
if(NOT anchor)
  message(FATAL_ERROR "plant_mprgp: no 'double product_dot(...) {' in ${SOURCE}: update the anchor")
endif()
string(REPLACE "${anchor}" "${anchor}\n        cb_plant::before_cg_product(m_A, v, m_cnt);" text "${text}")
string(SUBSTRING "${text}" 0 ${at_namespace} head)
string(SUBSTRING "${text}" ${at_namespace} -1 tail)
file(WRITE "${OUTPUT}.tmp" "// Generated from ${SOURCE} by tests/perf/plant_mprgp.cmake: the planted copy.\n"
     "${head}#include \"${PLANT}\"\n\n${tail}")
file(RENAME "${OUTPUT}.tmp" "${OUTPUT}")
