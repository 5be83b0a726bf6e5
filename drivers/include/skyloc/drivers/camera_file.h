// The camera file: a TOML description of the image size, the lens model and the mount,
// read at start-up by describe, replay, simulate and the camera drivers. The format is
// documented in docs/CAMERA_FILE.md (config/camera-equidistant-185.toml is an example).
// Every error names the file, the key and the fix; unknown keys are errors, so a typo
// never silently falls back to a default.
#pragma once

#include <string>
#include <string_view>

#include "skyloc/dsp/lens.h"
#include "skyloc/platform/status.h"

namespace skyloc::drivers {

// Reads and validates a camera file (including the OCamCalib file it may name, relative
// to the camera file's directory). The result has passed dsp::Lens::Init.
Result<dsp::LensParams> LoadCameraFile(const char* path);

// The same from text already in memory. `source` names it in messages; `base_dir` is where
// a relative ocamcalib_file is looked up.
Result<dsp::LensParams> ParseCameraFile(std::string_view text, const char* source,
                                        const char* base_dir);

// Reads an OCamCalib toolbox calib_results.txt: the ss polynomial (count then
// coefficients), invpol (count then coefficients), centre "row column", affine "c d e",
// and optionally the image size "height width"; '#' lines are comments.
Result<dsp::OCamCalibModel> LoadOCamCalibFile(const char* path);

// The lens of an image that comes without a camera file, guessed from its shape (what
// describe, eval and surf1d assume): a 2:1 image is an equirectangular panorama, a
// square-ish one (aspect 0.74..1.35) an equidistant 185-degree fisheye whose image circle
// touches the short side; any other shape is an error naming `image` and the fix.
Result<dsp::LensParams> GuessLensForImage(int width, int height, const char* image);

// A camera file describing `lens` (its effective centre and radius, the mount), headed by
// the comment line `comment`, that LoadCameraFile reads back to the same lens. OCamCalib
// lenses are not written (their polynomial lives in a file of its own): kUnimplemented,
// naming the fix (copy the camera file and its calib_results.txt).
Result<std::string> CameraFileText(const dsp::Lens& lens, const char* comment);

// dsp::Lens::Init with its error turned into a Status naming `source` and the fix.
Status InitLens(const dsp::LensParams& params, const char* source, dsp::Lens* lens);

}  // namespace skyloc::drivers
