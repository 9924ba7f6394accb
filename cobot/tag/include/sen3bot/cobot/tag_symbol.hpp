#pragma once
// The QR symbol of a tag, shared by the printed tags and the simulated camera's.
#include <opencv2/core.hpp>

#include "sen3bot/cobot/tag.hpp"
#include "sen3bot/hal/result.hpp"

namespace sen3bot::cobot::detail {

// The symbol's modules, one pixel each (0 dark, 255 light), without a quiet zone: 25 x 25 for
// the tags' QR version 2 at error correction level H. Errors: a bad tag, or the encoder failed.
Status tag_symbol(const Tag& tag, cv::Mat& modules);

}  // namespace sen3bot::cobot::detail
