# The RTL testbenches' tile jobs: the bunny and the interpenetrating scene at 1080p, 32x32
# tiles, traced and dumped by golden (tilevis golden --dump-evu-jobs), afresh on every run (about 1 s).
foreach(scene bunny interpenetrating)
  set(dir ${OUT}/${scene})
  file(REMOVE ${dir}/evu_jobs.txt)
  file(MAKE_DIRECTORY ${dir})
  execute_process(COMMAND ${TILEVIS} trace ${SRC}/traces/scenes/${scene}.json -o ${dir}/${scene}.tvt
                  RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "tilevis trace ${scene}: exit ${rc}")
  endif()
  execute_process(COMMAND ${TILEVIS} golden ${dir}/${scene}.tvt --tile 32 -o ${dir}/golden --dump-evu-jobs ${dir}.tmp
                  RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "tilevis golden ${scene} --dump-evu-jobs: exit ${rc}")
  endif()
  file(RENAME ${dir}.tmp/evu_jobs.txt ${dir}/evu_jobs.txt)  # whole files only: a failed dump leaves none
  file(REMOVE_RECURSE ${dir}.tmp)
endforeach()
