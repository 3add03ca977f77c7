// The tools' JSON documents: built as nlohmann::ordered_json values (one library for every
// document the tools write and read) and written in the layout they have always had, so a
// reader can follow them line by line: the top-level members one a line, a nested object on
// its line, an array's elements one a line (seqslam eval/run's per-query matches). `numbers`:
// kShortest writes a double as the shortest text that reads back as it (nlohmann's own),
// kSixDigits as printf's %.6g (the evaluation's figures); an integer is an integer either way
// and a NaN or infinity is null.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

namespace seqslam::tools {

enum class JsonNumbers { kShortest, kSixDigits };

std::string json_text(const nlohmann::ordered_json& doc, JsonNumbers numbers);

// A decimal that is exactly what it says (e.g. a fixed-point setting's shortest decimal,
// "0.85"), as a JSON number that json_text writes back as that text.
double json_decimal(const std::string& text);

}  // namespace seqslam::tools
