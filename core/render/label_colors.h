#pragma once
// Colours for `style.colormap: "label"`: a fixed categorical palette (a
// label keeps its colour in every frame, run and scenario) and the key drawn
// in place of a colour scale. Each boundary face takes its tet's label.
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "core/model/model.h"

namespace organsim {

// RGB in [0, 1]. Label 0 (an unlabelled mesh's every tet) is a light grey;
// labels 1..7 are Okabe and Ito's colour-blind safe colours (orange, sky
// blue, bluish green, yellow, blue, vermillion, reddish purple); from 8 on
// the seven repeat (label 8 is label 1's orange).
Vec3f label_rgb(int32_t label);

// The label of each boundary face's owning tet (0 when the model has no labels).
std::vector<int32_t> face_labels(const Model& model, const std::vector<int32_t>& face_tet);

// The key at the right edge of a BGR image: one swatch and "label N" per
// label in `labels` (ascending, each once), under the title "label".
void draw_label_key(cv::Mat& bgr, const std::vector<int32_t>& labels);

}  // namespace organsim
