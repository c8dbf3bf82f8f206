# tests of the sphere component (src/capture/include/capture/sphere_silhouette.h)
clayfit_c_test(test_sphere_fit SOURCES capture/test_sphere_fit.c
               LIBS clayfit_sphere m LABELS capture)
clayfit_c_test(test_sphere_detect SOURCES capture/test_sphere_detect.c
               LIBS clayfit_sphere m LABELS capture)
clayfit_c_test(test_sphere_dark_limb SOURCES capture/test_sphere_dark_limb.c
               LIBS clayfit_sphere clayfit_image m LABELS capture)
# The real DiLiGenT ball (skipped without ../shared/data): its mask is read
# with OpenCV's imgcodecs, in a test-only C++ helper.
find_package(OpenCV REQUIRED COMPONENTS core imgproc imgcodecs)
clayfit_c_test(test_sphere_diligent
               SOURCES capture/test_sphere_diligent.c capture/sphere_diligent_cv.cpp
               LIBS clayfit_sphere ${OpenCV_LIBS} m LABELS capture
               ARGS ${CLAYFIT_SHARED_DATA})
target_include_directories(test_sphere_diligent SYSTEM PRIVATE ${OpenCV_INCLUDE_DIRS})
