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
# 250 MB runs out of memory, a failure while running (exit 1), not a bad
# input (it fits in 350 MB since its observations' arrays are allocated
# once, not doubled).
if(NOT CLAYFIT_SANITIZE)
  add_test(NAME capture_hostile_bomb_png_2gb
           COMMAND ${CHECK} --exit 2 --stderr "001.png: the image is 26000 x 26000 pixels" --
                   /bin/sh -c "ulimit -v 2000000 && exec \"$0\" \"$@\"" ${CLAYFIT} inspect
                   --no-overlays ${HOSTILE}/bomb_png/capture.json)
  set_tests_properties(capture_hostile_bomb_png_2gb PROPERTIES LABELS capture
                       FIXTURES_REQUIRED hostile_captures)
  string(JOIN " " check_command ${CHECK})
  add_test(NAME capture_hostile_out_of_memory
           COMMAND /bin/sh -c "test -f \"$2\" || { echo 'no DiLiGenT data: skipped'; exit 77; }; exec ${check_command} --exit 1 --stderr 'out of memory' -- /bin/sh -c 'ulimit -v 250000 && exec \"$0\" \"$@\"' \"$0\" inspect --no-overlays \"$1\""
                   ${CLAYFIT} ${CMAKE_CURRENT_SOURCE_DIR}/diligent_ball.capture.json
                   ${CLAYFIT_SHARED_DATA}/diligent_ball/filenames.txt)
  set_tests_properties(capture_hostile_out_of_memory PROPERTIES LABELS capture
                       SKIP_RETURN_CODE 77)
endif()

# Issue 30, item 5: a JPEG cut short or with noise in its coded data is
# refused (exit 2, naming the file), not decoded as grey. clayfit's codec
# fails the read on any libjpeg warning (image_jpeg.c).
hostile_loads(jpeg_ok)
hostile_capture(jpeg_cut_scan 2 "jpeg_cut_scan/images/001.jpg: decoding failed: libjpeg: Premature end of JPEG file")
hostile_capture(jpeg_half 2 "jpeg_half/images/001.jpg: decoding failed: libjpeg: Premature end of JPEG file")
hostile_capture(jpeg_no_eoi 2 "jpeg_no_eoi/images/001.jpg: decoding failed: libjpeg: Premature end of JPEG file")
hostile_capture(jpeg_noise 2 "jpeg_noise/images/001.jpg: decoding failed: libjpeg: Corrupt JPEG data")
hostile_capture(jpeg_noise_run 2 "jpeg_noise_run/images/001.jpg: decoding failed: libjpeg: Corrupt JPEG data")
# item 8: each EXIF field bounded to what cameras record, and an exposure
# more than 2^16 from the capture's median refused
hostile_capture(exif_time_huge 2 "exif_time_huge/images/001.jpg: the EXIF exposure time \\(tag 0x829A\\) is 4294967296 s, outside \\[1e-06, 3600\\] s")
hostile_capture(exif_time_tiny 2 "exif_time_tiny/images/001.jpg: the EXIF exposure time \\(tag 0x829A\\) is 2.3283064[0-9]*e-10 s, outside \\[1e-06, 3600\\] s")
hostile_capture(exif_f_huge 2 "exif_f_huge/images/001.jpg: the EXIF f-number \\(tag 0x829D\\) is 4294967296, outside \\[0.5, 256\\]")
hostile_capture(exif_iso_huge 2 "exif_iso_huge/images/001.jpg: the EXIF ISO \\(tag 0x8827\\) is 4294967296, outside \\[1, 1e\\+07\\]")
hostile_capture(exif_spread 2 "exif_spread/images/001.jpg: its EXIF exposure .* is [0-9.e+]+ times above the capture's median .*at most 65536")
# item 13: a NaN in an environment map is refused, not set to 0
hostile_loads(env_ok)
hostile_capture(env_nan 2 "env_nan/sky.pfm: environment map: 1 non-finite value \\(NaN or infinity\\); the first is NaN at texel \\(5, 21\\) \\(column, row from the top-left\\), channel 2 \\(B\\)")
# item 10: the maps' headers read before any decoding, their sizes against
# the images' and their decoded bytes counted in the cap
hostile_capture(normal_bomb 2 "normal_bomb/normals.png: the normal map is 26000 x 26000 pixels but .*000.png is 32 x 32 \\(from its header, before decoding\\)")
hostile_capture(env_bomb 2 "env_bomb/capture.json: the maps up to the environment map .*env_bomb/sky.png \\(26000 x 26000 x 3\\) decode to 8.11 GB .*more than the cap of 1 GB" --max-image-memory 1)
add_test(NAME capture_hostile_map_cap
         COMMAND ${CHECK} --exit 2 --stderr "env_ok/capture.json: the maps and the images up to 000.png \\(1 of 3; 32 x 32 x 1 the last\\) and their masks decode to 4.1e-05 GB.*more than the cap of 4e-05 GB" --
                 ${CLAYFIT} inspect --max-image-memory 0.00004 ${HOSTILE}/env_ok/capture.json)
set_tests_properties(capture_hostile_map_cap PROPERTIES LABELS "capture;cli"
                     FIXTURES_REQUIRED hostile_captures)
