# clayfit_colmap: COLMAP sparse models (text, binary) and camera models.
# Pure C (libc and libm only).
add_library(clayfit_colmap STATIC
  ${CMAKE_CURRENT_LIST_DIR}/camera_model.c
  ${CMAKE_CURRENT_LIST_DIR}/colmap_common.c
  ${CMAKE_CURRENT_LIST_DIR}/colmap_text.c
  ${CMAKE_CURRENT_LIST_DIR}/colmap_binary.c
  ${CMAKE_CURRENT_LIST_DIR}/colmap_read.c
  ${CMAKE_CURRENT_LIST_DIR}/colmap_write.c)
target_link_libraries(clayfit_colmap PUBLIC clayfit_core m PRIVATE clayfit_warnings)
