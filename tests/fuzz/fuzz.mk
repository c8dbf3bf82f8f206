# The libFuzzer targets and their seed writers: the one place for their
# sources and flags. scripts/fuzz.sh runs it (from the project's root):
#   make -f tests/fuzz/fuzz.mk -j N OUT=build/fuzz CC=clang CXX=clang++
# clayfit's sources are compiled here with libFuzzer's coverage, ASan and
# UBSan (their own CMake builds do not change), into OUT/obj, rebuilt when
# a source or a header it includes changes. Jansson and the image
# libraries (libpng, libjpeg, OpenEXR) are Debian's, linked uninstrumented.
OUT ?= build/fuzz
OBJ := $(OUT)/obj

SANITIZE := -fsanitize=address,undefined -fno-sanitize-recover=undefined
# the layers' interfaces (src/*/include) and, for the white-box harnesses, src/
INCLUDES := -Iinclude $(patsubst %,-I%,$(wildcard src/*/include)) -Isrc
COMMON := -g -O1 -fno-omit-frame-pointer -Wall -Wextra -Werror $(INCLUDES) -MMD -MP
CFLAGS := -std=c11 -D_POSIX_C_SOURCE=200809L $(COMMON)
CXXFLAGS := -std=c++17 $(COMMON) $(shell pkg-config --cflags OpenEXR)
INSTRUMENT := -fsanitize=fuzzer-no-link $(SANITIZE)
LIBS := -Wl,--as-needed $(shell pkg-config --libs libpng OpenEXR) -ljpeg -ljansson -ldl -lm

CORE := src/core/status.c src/core/file.c src/core/json_reader.c src/core/text_escape.c src/core/order_statistics.c
# the model without its least-squares fits (tailed_ggx.c is clayfit_model_fit, on lsq and Ceres)
MODEL := $(filter-out src/model/tailed_ggx.c,$(wildcard src/model/*.c))
# the STD masking's grid, generated as the CMake build does (src/model/CMakeLists.txt)
GRID := $(OUT)/gen/tailed_grid.c
COLMAP := src/capture/camera_model.c src/capture/colmap_common.c src/capture/colmap_binary.c \
          src/capture/colmap_text.c src/capture/colmap_read.c
COLMAP_WRITE := src/capture/colmap_write.c
IMAGE := src/capture/image_io.c src/capture/image_codec.c src/capture/image_png.c \
         src/capture/image_pfm.c src/capture/image_jpeg.c src/capture/image_exif.c \
         src/capture/image_exr.cpp src/capture/image_exr_check.c src/capture/image_check.c \
         src/capture/colour.c src/capture/envmap.c src/capture/jpeg_coding.c
CAPTURE_SPEC := src/capture/capture_spec.c src/capture/capture_spec_lights.c
CAPTURE_FILES := $(CAPTURE_SPEC) src/capture/capture_lights.c src/capture/lights.c
FIT_READ := src/fit/fit_read.c src/fit/fit_read_sections.c src/fit/fit_read_choice.c \
            src/fit/fit_result.c src/fit/fit_response.c

# target: its harness, then the sources it reads with
fuzz_colmap_binary := tests/fuzz/fuzz_colmap_binary.c $(COLMAP) $(CORE)
fuzz_capture_spec := tests/fuzz/fuzz_capture_spec.c $(CAPTURE_SPEC) $(IMAGE) $(CORE)
fuzz_text := tests/fuzz/fuzz_text.c tests/fuzz/fuzz_stubs.c $(CAPTURE_FILES) $(IMAGE) $(CORE)
fuzz_fit_file := tests/fuzz/fuzz_fit_file.c $(FIT_READ) $(MODEL) $(GRID) $(CORE)
fuzz_image := tests/fuzz/fuzz_image.cpp $(IMAGE) $(CORE)
TARGETS := fuzz_colmap_binary fuzz_capture_spec fuzz_text fuzz_fit_file fuzz_image

# seed writers (clayfit's own writers, no libFuzzer main)
make_seeds := tests/fuzz/make_seeds.c $(COLMAP) $(COLMAP_WRITE) $(CORE)
make_image_seeds := tests/fuzz/make_image_seeds.c $(IMAGE) $(CORE)
WRITERS := make_seeds make_image_seeds

objects = $(patsubst %,$(OBJ)/%.o,$(basename $(1)))

all: $(addprefix $(OUT)/,$(TARGETS) $(WRITERS))

define link_target
$(OUT)/$(1): $(call objects,$($(1)))
	$$(CXX) $(2) $$^ $(LIBS) -o $$@
endef
$(foreach t,$(TARGETS),$(eval $(call link_target,$(t),-fsanitize=fuzzer $(SANITIZE))))
$(foreach t,$(WRITERS),$(eval $(call link_target,$(t),-fsanitize=fuzzer-no-link $(SANITIZE))))

$(OUT)/gen/tailed_grid_gen: tools/tailed_grid_gen.c src/model/tailed.c tests/fuzz/fuzz.mk
	@mkdir -p $(@D)
	$(CC) -std=c11 -O2 -ffp-contract=off $(INCLUDES) -Isrc/model $(filter %.c,$^) -lm -o $@

$(GRID): $(OUT)/gen/tailed_grid_gen
	$< $@

# the grid includes the model's private tailed.h, as in src/model
$(call objects,$(GRID)): CFLAGS += -Isrc/model

$(OBJ)/%.o: %.c tests/fuzz/fuzz.mk
	@mkdir -p $(@D)
	$(CC) $(CFLAGS) $(INSTRUMENT) -c $< -o $@

$(OBJ)/%.o: %.cpp tests/fuzz/fuzz.mk
	@mkdir -p $(@D)
	$(CXX) $(CXXFLAGS) $(INSTRUMENT) -c $< -o $@

-include $(shell find $(OBJ) -name '*.d' 2>/dev/null)

.PHONY: all
.DELETE_ON_ERROR:
