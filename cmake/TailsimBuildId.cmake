# tailsim_build_id(HEADER): a target `tailsim_git_commit` that (re)writes HEADER with kGitCommit on
# every build (cmake/tailsim_git_commit.cmake), so an incremental build after a commit or an edit
# carries the new identity without reconfiguring. Targets that include HEADER depend on it.
function(tailsim_build_id header)
  execute_process(COMMAND ${CMAKE_COMMAND} -DSOURCE_DIR=${PROJECT_SOURCE_DIR} -DOUT=${header}
                          -P ${CMAKE_CURRENT_FUNCTION_LIST_DIR}/tailsim_git_commit.cmake)  # present at configure
  add_custom_target(tailsim_git_commit
                    COMMAND ${CMAKE_COMMAND} -DSOURCE_DIR=${PROJECT_SOURCE_DIR} -DOUT=${header}
                            -P ${CMAKE_CURRENT_FUNCTION_LIST_DIR}/tailsim_git_commit.cmake
                    BYPRODUCTS ${header}
                    COMMENT "" VERBATIM)
endfunction()
