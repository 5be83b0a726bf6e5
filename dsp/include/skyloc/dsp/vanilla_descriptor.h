// The paper's baseline, "SeqSLAM (vanilla)": the image as OpenSeqSLAM preprocesses it.
// Greyscale, reduced to 64x32 by area averaging, then patch-normalised: every 8x8 patch
// becomes (pixel - patch mean) / patch std. Two descriptors are compared by their (mean)
// absolute difference, which is what DifferenceColumn in seqslam.h computes.
//
// Differences from OpenSeqSLAM's preprocessing (openSeqSLAM.m, patchNormalize):
//  - area averaging instead of imresize's Lanczos-3 (OpenSeqSLAM's sample datasets come
//    pre-resized; its DO_RESIZE defaults to 0);
//  - the normalised values stay float. OpenSeqSLAM stores 127 + round(z) in uint8, which
//    keeps about three grey levels per patch;
//  - a flat patch (std 0) gives zeros; OpenSeqSLAM's 0/0 turns into 0 by the uint8 cast.
#pragma once

#include <cstdint>
#include <span>

#include "skyloc/dsp/image.h"

namespace skyloc::dsp {

inline constexpr int kVanillaWidth = 64;
inline constexpr int kVanillaHeight = 32;
inline constexpr int kVanillaPatch = 8;
inline constexpr int kVanillaDescriptorSize = kVanillaWidth * kVanillaHeight;  // 2048

enum class VanillaError : std::uint8_t {
  kOk = 0,
  kEmptyImage,     // no pixels, or a stride shorter than a row
  kBadOutputSize,  // out.size() != kVanillaDescriptorSize
};

const char* VanillaErrorMessage(VanillaError error);

// Luminance of one pixel (ITU-R BT.601 weights 0.299, 0.587, 0.114 as MATLAB's rgb2gray;
// Y for YUYV), 0..255.
float PixelLuminance(const ImageView& image, int x, int y);

// Area-averaging resize of the image's luminance to out_width x out_height (out row by
// row): each output pixel is the mean over the source area it covers, partial pixels
// weighted by the covered fraction. Works for shrinking and enlarging. Returns false for an
// empty image or a wrong out size.
bool AreaResizeLuminance(const ImageView& image, int out_width, int out_height,
                         std::span<float> out);

// out: 32 rows of 64 values, row by row. Allocates nothing.
VanillaError VanillaDescriptor(const ImageView& image, std::span<float> out);

// Sum of absolute differences of two descriptors of equal length.
float SumAbsoluteDifference(std::span<const float> a, std::span<const float> b);

}  // namespace skyloc::dsp
