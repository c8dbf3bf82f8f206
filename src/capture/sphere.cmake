# clayfit_sphere: sphere silhouettes (OpenCV) and their triangulation.
# sphere_detect.cpp (with sphere_edges.cpp and sphere_hough.cpp, which share
# sphere_detect_internal.hpp) is a thin C++ adapter over OpenCV (core,
# imgproc) with C linkage; sphere_fit.c is pure C and solves through src/lsq.
add_library(clayfit_sphere STATIC sphere_detect.cpp sphere_edges.cpp sphere_hough.cpp
            sphere_fit.c sphere_robust.c)
target_include_directories(clayfit_sphere SYSTEM PRIVATE ${OpenCV_INCLUDE_DIRS})
target_link_libraries(clayfit_sphere PUBLIC clayfit_core
                      PRIVATE clayfit_lsq ${OpenCV_LIBS} clayfit_warnings m)
