#include "fpp/calib/decode_options.hpp"

#include "fpp/error.hpp"

namespace fpp::calib {

void check_decode_options(const DecodeOptions& options, OptionSpelling spelling,
                          const std::string& origin) {
    try {
        options.validate();
    } catch (const InputError& e) { // the field of DecodeOptions: name the option instead
        const std::string& field = e.field();
        std::string option;
        if (spelling == OptionSpelling::keyword)
            option = field;
        else
            option = field == "min_modulation" ? "--min-modulation"
                     : field == "threads"      ? "--threads"
                                               : "decode options: " + field;
        std::string what = e.what();
        const std::string prefix = e.file().string() + ": " + field + ": ";
        if (what.starts_with(prefix))
            what.erase(0, prefix.size());
        throw InputError(spelling == OptionSpelling::keyword ? origin : "command line", option,
                         what);
    }
}

} // namespace fpp::calib
