#pragma once
// The files `fpp-calib decode` writes (a stable, documented interface):
//   proj_x.tiff, proj_y.tiff  float32, camera resolution, projector pixels, NaN invalid
//   modulation.tiff           float32, DN
//   mask.png                  8-bit, 255 where decoded, 0 elsewhere
//   flags.png                 8-bit, DecodeFlag bits per pixel (fpp/decoder.hpp)
//   proj_x.png, proj_y.png, modulation.png   false-colour previews
//   decode.md                 summary; with ground truth, the error against it

#include "fpp/capture_set.hpp"
#include "fpp/decoder.hpp"

#include <filesystem>
#include <string>

namespace fpp::calib {

// Writes the images above (each atomically) into `folder` (created if needed).
void write_decode_images(const std::filesystem::path& folder, const DecodeResult& result,
                         const CaptureManifest& manifest);

// Markdown summary of a decode; compares with the capture's truth when it has
// one. `capture_folder` locates the truth files.
std::string decode_summary(const DecodeResult& result, const CaptureSet& capture,
                           double decode_seconds);

} // namespace fpp::calib
