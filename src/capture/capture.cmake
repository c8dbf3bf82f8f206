# clayfit_capture: capture files, lights, the sphere's surface, observations,
# overlays, and synthetic captures.
find_package(Threads REQUIRED)
target_sources(clayfit_capture PRIVATE
  capture_spec.c capture_spec_lights.c capture_files.c capture.c capture_images.c
  capture_views.c capture_lights.c capture_surface.c capture_reference.c capture_radiance.c
  observations.c capture_screen.c capture_turn.c overlay.c synth.c synth_render.c synth_files.c
  synth_scene.c chrome_ball.c)
target_link_libraries(clayfit_capture PRIVATE PkgConfig::JANSSON Threads::Threads)
