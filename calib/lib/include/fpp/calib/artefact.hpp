#pragma once
// A certified test artefact for verifying a scanner after VDI/VDE 2634 part 2
// (`fpp-calib verify`): a ball bar, a single sphere or a flat plate, with
// the sizes its calibration certificate gives. File format `fpp-artefact/1`:
// firmware/core/formats/artefact.md. Lengths in mm.

#include <filesystem>
#include <string>
#include <vector>

namespace fpp::calib {

enum class ArtefactKind { ball_bar, sphere, plane };

// "ball-bar", "sphere", "plane".
const char* to_string(ArtefactKind kind);

struct Artefact {
    std::filesystem::path origin; // the file it was read from (named in errors)
    ArtefactKind kind = ArtefactKind::ball_bar;
    std::string name;                        // optional label (serial number); may be empty
    std::vector<double> sphere_diameters_mm; // ball bar: 2, sphere: 1, plane: none
    double centre_distance_mm = 0;           // ball bar only
    double plane_width_mm = 0;               // plane only: its size
    double plane_height_mm = 0;              //
    double flatness_mm = 0;                  // plane only: its certified flatness
    double uncertainty_mm = 0;               // of the certificate's values, 1 sigma

    std::size_t sphere_count() const { return sphere_diameters_mm.size(); }
};

// Reads and checks an artefact file. Throws InputError(file, key, why) for a
// file that cannot be read, malformed YAML, an unknown format, kind or key, a
// key the kind does not have or lacks, and values out of range (see
// artefact.md); IoError for OS failures.
Artefact read_artefact(const std::filesystem::path& path);

// The same from text; `origin` names it in errors.
Artefact parse_artefact(const std::string& text, const std::filesystem::path& origin);

} // namespace fpp::calib
