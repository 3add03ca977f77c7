// The settings' values as text, read and written exactly: decimals as exact ratios, the
// shortest decimal that reads back as a fixed-point value, image sizes, the preprocessing's
// names, wheel constants. What the settings' options (settings_cli.h) and the tools' messages
// use. Each parse returns an empty string on success, else what is wrong (for CLI11
// validators and usage errors).
#pragma once

#include <stdint.h>

#include <string>
#include <vector>

#include "seqslam/fixed.h"
#include "seqslam/odometry.h"
#include "seqslam/preprocess.h"

namespace seqslam::cli {

// ---------------------------------------------------------------------------------------
// Parsing.

// Wheel constants "LEFT,RIGHT,TRACK" in metres (circumferences and track width) into `out`'s
// three constants; false for anything else or a value out of range (circumferences 0..16,
// track 0..100). (seqslam slam --wheels / --true-wheels, config write --wheels.)
bool parse_wheel_constants(const std::string& text, OdometryConfig* out);
// The same text of `c`'s constants, 9 decimals (what parse_wheel_constants reads).
std::string wheel_constants_text(const OdometryConfig& c);
// Image size "WxH" for the FPGA pixel buffer: both sides >= 1 and W * H <= 512.
std::string parse_image_size(const std::string& text, uint16_t* width, uint16_t* height);
// A decimal "[-]digits[.digits]" (at most 18 digits) as the exact ratio num / den.
std::string parse_decimal(const std::string& text, int64_t* num, int64_t* den);
// A confidence threshold: a decimal within 0..1, converted exactly as the library's default
// is (UQ16_16::from_ratio, so "0.85" gives the default's value).
std::string parse_threshold(const std::string& text, UQ16_16* threshold);
// The route search's growth (places per place travelled without a fix) as UQ8.8 (steps of
// 1/256), rounded to the nearest step as from_ratio does; refused when that would not keep
// the value: negative, rounding beyond 65535/256, or positive but rounding to 0.
std::string parse_route_growth(const std::string& text, UQ8_8* growth);
// The route search's start: a whole number within int32 (a library place; -1 is unknown) or
// "unknown" (-1). Other negative numbers are left to the caller (config write passes them to
// check_localiser_config, which names the valid range).
std::string parse_route_start(const std::string& text, int32_t* start);

// The preprocessing methods by name ("none", "he", "pn", ...), in enum order, and the method
// of a name (false for an unknown one, *out unchanged).
std::vector<std::string> preprocessing_names();
bool parse_preprocessing(const std::string& name, Preprocessing* out);

// ---------------------------------------------------------------------------------------
// Exact decimal formatting of fixed-point values (integer arithmetic only).

// raw / 2^frac_bits rounded to `decimals` digits after the point (ties to even).
std::string fixed_decimal(int64_t raw, unsigned frac_bits, unsigned decimals);
// The shortest decimal that reads back as `raw` (round to nearest), e.g. 0.85 for the
// UQ16.16 threshold from_ratio(85, 100).
std::string shortest_decimal(int64_t raw, unsigned frac_bits);
// raw / 2^frac_bits in full (a binary fraction has a finite decimal), no trailing zeros:
// 0.05078125 for the UQ8.8 value 13.
std::string exact_decimal(int64_t raw, unsigned frac_bits);
// A binary angle (2^32 per turn) in degrees within [-180, 180), `decimals` digits.
std::string angle_degrees(uint32_t bam, unsigned decimals);

}  // namespace seqslam::cli
