/* The note of a tailed lobe in the GGX-only formats (src/export/
 * export_mapping.c, docs/presets.md "Tailed lobes in GGX-only formats"): the
 * one wording of the loss, the approximate note with the GGX written, and
 * at tail 2 (GGX itself) an exact note with a loss of 0. The GGX itself is
 * tested in tests/test_tailed_ggx.c. */
#include <string.h>

#include "export/export_internal.h"
#include "support/check.h"

CHECK_MAIN_STATE;

static void test_note(void) {
  char text[96];
  export_ggx_loss_text(0.061, text, sizeof text);
  CHECK(!strcmp(text, "GGX approximation: 6.1 % RMS over the lobe"), "'%s'", text);
  export_ggx_loss_text(0.0003, text, sizeof text);
  CHECK(!strcmp(text, "GGX approximation: < 0.1 % RMS over the lobe"), "'%s'", text);
  export_ggx_loss_text(0.0, text, sizeof text);
  CHECK(!strcmp(text, "GGX approximation: 0 % RMS over the lobe"), "'%s'", text);
  preset_notes notes = {0};
  export_note_tailed(&notes, "the specular lobe", 0.3, 1.7, 0.04, 0.331, 0.0398, 0.196);
  CHECK(notes.count == 1 && notes.kind[0] == PRESET_APPROX &&
            strstr(notes.text[0], "the specular lobe: tailed (roughness 0.3, tail gamma 1.7") &&
            strstr(notes.text[0],
                   "roughness 0.331, F0 0.0398; GGX approximation: 19.6 % RMS "
                   "over the lobe"),
        "note '%s'", notes.text[0]);
  /* tail 2 is GGX: an exact note, the same line with 0 */
  export_note_tailed(&notes, "the film's lobe", 0.3, 2.0, 0.04, 0.3, 0.04, 0.0);
  CHECK(notes.count == 2 && notes.kind[1] == PRESET_EXACT &&
            strstr(notes.text[1], "the film's lobe: tail gamma 2 is GGX") &&
            strstr(notes.text[1], "GGX approximation: 0 % RMS over the lobe"),
        "note '%s'", notes.text[1]);
}

int main(void) {
  test_note();
  return check_finish("test_tailed_note");
}
