// Text drawn into images: the labels of `--compare` tiles and the legend that fills a spare
// tile, so a composite says what each tile is without the console output. A built-in 5x7
// bitmap font (upper case, digits, a little punctuation; lower case is drawn upper case,
// anything else as a blank), scaled by whole pixels.
#ifndef PDSM_CLIENT_VIEW_TEXT_OVERLAY_H_
#define PDSM_CLIENT_VIEW_TEXT_OVERLAY_H_

#include <string>
#include <vector>

#include "client/view/image_io.h"

namespace pdsm::view {

// Width and height in pixels of `text` at `scale` (one line).
int TextWidth(const std::string& text, int scale);
int TextHeight(int scale);

// Draws `text` with its top-left corner at (x, y), white on a box that darkens what is under
// it, clipped to the image.
void DrawLabel(RgbImage* image, int x, int y, const std::string& text, int scale);

// Draws lines of text from (x, y) down, in light grey, without a box.
void DrawText(RgbImage* image, int x, int y, const std::vector<std::string>& lines, int scale);

// A scale that keeps labels readable on a `tile_height`-pixel tile: 1 up to 150 pixels, then one
// more per 150.
int LabelScale(int tile_height);

}  // namespace pdsm::view

#endif  // PDSM_CLIENT_VIEW_TEXT_OVERLAY_H_
