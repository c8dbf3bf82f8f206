# Hostile input to captures (issue 16, items 11, 12 and 14): one small
# capture per case (make_hostile_captures.py says how each is broken),
# `clayfit inspect` on it, its exit status and message.
set(HOSTILE ${CMAKE_CURRENT_BINARY_DIR}/hostile_captures)
add_test(NAME make_hostile_captures
         COMMAND ${CLAYFIT_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/capture/make_hostile_captures.py
                 ${CLAYFIT} ${HOSTILE})
set_tests_properties(make_hostile_captures PROPERTIES LABELS capture
                     FIXTURES_SETUP hostile_captures)

# hostile_capture(case exit stderr-regex [inspect options...])
function(hostile_capture case exit regex)
  add_test(NAME capture_hostile_${case}
           COMMAND ${CHECK} --exit ${exit} --stderr "${regex}" --
                   ${CLAYFIT} inspect --no-overlays ${ARGN} ${HOSTILE}/${case}/capture.json)
  set_tests_properties(capture_hostile_${case} PROPERTIES LABELS capture
                       FIXTURES_REQUIRED hostile_captures)
endfunction()
# item 12: the header's size against the camera's, before decoding; the cap
hostile_capture(bomb_png 2 "bomb_png/images/001.png: the image is 26000 x 26000 pixels but its COLMAP camera 1 is 96 x 72 \\(from its header, before decoding\\)")
add_test(NAME capture_hostile_image_cap
         COMMAND ${CHECK} --exit 2 --stderr "fine/capture.json: the images up to 001.png \\(2 of 3.*more than the cap of 0.0002 GB.*--max-image-memory" --
                 ${CLAYFIT} inspect --max-image-memory 0.0002 ${HOSTILE}/fine/capture.json)
set_tests_properties(capture_hostile_image_cap PROPERTIES LABELS "capture;cli"
                     FIXTURES_REQUIRED hostile_captures)
add_test(NAME capture_hostile_cap_value
         COMMAND ${CHECK} --exit 2 --stderr "--max-image-memory: 0 GB is outside \\(0, 1e9\\]" --
                 ${CLAYFIT} inspect --max-image-memory 0 ${HOSTILE}/fine/capture.json)
set_tests_properties(capture_hostile_cap_value PROPERTIES LABELS "capture;cli")
# item 11: one file listed twice is an error (it would count twice)
hostile_capture(duplicate_image 2 "images 1 \\(000.png\\) and 3 \\(000.png\\) are the same file")
# item 14
hostile_capture(truncated_png 2 "truncated_png/images/001.png: a truncated PNG: chunk 'IDAT' at byte [0-9]+ needs [0-9]+ bytes but the file ends at byte [0-9]+")
hostile_capture(huge_radius 2 "geometry.radius: 1e\\+308 is outside \\[1e-300, 1e\\+300\\]")
hostile_capture(bom_colmap 2 "image '.*000.png' \\(the name holds a UTF-8 byte-order mark \\(U\\+FEFF, bytes EF BB BF\\) at byte 0\\) is not in the COLMAP model")
hostile_capture(bom_path 2 "bom_path/.*000.png: no such file \\(the name holds a UTF-8 byte-order mark \\(U\\+FEFF, bytes EF BB BF\\) at byte [0-9]+\\)")
hostile_capture(text_nul 2 "text_nul/light_directions.txt:2: a NUL byte at byte offset 21")
hostile_capture(text_rows 2 "text_rows/light_directions.txt: 2 rows \\(lines not blank and not '#' comments\\) for the 3 images of .*text_rows/filenames.txt")

# hostile_loads(case [--expect ...]): the capture loads (exit 0), with
# observations; --expect over inspect's JSON (its warnings).
function(hostile_loads case)
  add_test(NAME capture_hostile_${case}
           COMMAND ${CHECK} --expect "doc['observations'] > 0" ${ARGN} --
                   ${CLAYFIT} --quiet inspect --json --no-overlays ${HOSTILE}/${case}/capture.json)
  set_tests_properties(capture_hostile_${case} PROPERTIES LABELS capture
                       FIXTURES_REQUIRED hostile_captures)
endfunction()
hostile_loads(text_ok --expect "doc['warnings'] == []")
hostile_loads(text_subnormal)
hostile_loads(text_comment --expect "len(doc['images']) == 3")
hostile_loads(text_bom --expect "len(doc['images']) == 3")
hostile_loads(black_mask --expect "any('black_mask/masks/001.png: no pixel of this mask is usable' in w for w in doc['warnings'])")
hostile_loads(mixed_depth --expect "any('the images mix sample types: 1 8-bit (001.png), 2 16-bit (the first 000.png)' in w for w in doc['warnings'])")

# Under a memory limit (not with the sanitizers: they reserve terabytes of
# address space). The bomb is refused under 2 GB; decoding DiLiGenT under
# 400 MB runs out of memory, a failure while running (exit 1), not a bad
# input (it fits in 600 MB since OpenImageIO's libraries are not mapped).
if(NOT CLAYFIT_SANITIZE)
  add_test(NAME capture_hostile_bomb_png_2gb
           COMMAND ${CHECK} --exit 2 --stderr "001.png: the image is 26000 x 26000 pixels" --
                   /bin/sh -c "ulimit -v 2000000 && exec \"$0\" \"$@\"" ${CLAYFIT} inspect
                   --no-overlays ${HOSTILE}/bomb_png/capture.json)
  set_tests_properties(capture_hostile_bomb_png_2gb PROPERTIES LABELS capture
                       FIXTURES_REQUIRED hostile_captures)
  string(JOIN " " check_command ${CHECK})
  add_test(NAME capture_hostile_out_of_memory
           COMMAND /bin/sh -c "test -f \"$2\" || { echo 'no DiLiGenT data: skipped'; exit 77; }; exec ${check_command} --exit 1 --stderr 'out of memory' -- /bin/sh -c 'ulimit -v 400000 && exec \"$0\" \"$@\"' \"$0\" inspect --no-overlays \"$1\""
                   ${CLAYFIT} ${CMAKE_CURRENT_SOURCE_DIR}/diligent_ball.capture.json
                   ${CLAYFIT_SHARED_DATA}/diligent_ball/filenames.txt)
  set_tests_properties(capture_hostile_out_of_memory PROPERTIES LABELS capture
                       SKIP_RETURN_CODE 77)
endif()
