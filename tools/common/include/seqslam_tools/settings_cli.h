// The settings table (storage/run_config.h) on the command line: every subcommand's options
// for the settings it uses, `config show`'s rows and the `config write` options that
// reproduce a configuration are made here from the table, so a setting's name, range, help
// and default are written once (in the table) and read the same way everywhere.
//
// Values read exactly: a Fixed setting is a decimal rounded to its Q format as the library's
// from_ratio rounds (so "0.85" is the core's default threshold bit for bit), an Angle is in
// degrees, an enum or a bit set by the names the table gives, a place index or "unknown".
// Out of range, or a positive value that would round to 0, is a usage error naming the range.
#pragma once

#include <CLI/CLI.hpp>

#include <map>
#include <type_traits>
#include <memory>
#include <string>
#include <vector>

#include "seqslam/storage/run_config.h"
#include "seqslam/storage/settings_codec.h"

namespace seqslam::cli {

// ---------------------------------------------------------------------------------------
// One setting's value as text, by its field's type (settings_cli.cpp). parse() returns "" and
// sets *out, or says what is wrong (*out unchanged); text() is what parse() reads back.

namespace setting_text {

std::string parse(const std::string& text, const storage::Setting& s, uint8_t* out);
std::string parse(const std::string& text, const storage::Setting& s, bool* out);
std::string parse(const std::string& text, const storage::Setting& s, uint16_t* out);
std::string parse(const std::string& text, const storage::Setting& s, uint32_t* out);
std::string parse(const std::string& text, const storage::Setting& s, int32_t* out);
std::string parse(const std::string& text, const storage::Setting& s, Angle* out);
std::string parse(const std::string& text, const storage::Setting& s, storage::TriggerMode* out);
std::string parse(const std::string& text, const storage::Setting& s, LocaliserMatcher* out);
std::string parse(const std::string& text, const storage::Setting& s, hal::PipelineMapping* out);
std::string parse(const std::string& text, const storage::Setting& s, PreprocessConfig* out);
std::string parse(const std::string& text, const storage::Setting& s, OdometryConfig* out);
std::string parse(const std::string& text, const storage::Setting& s, storage::MapOrigin* out);
std::string parse(const std::string& text, const storage::Setting& s, storage::MapSize* out);
std::string text_of_degrees(uint32_t bam);

// The range a setting takes, as --help shows it after the option's type ("1..100",
// "0..1000", "diagonal|heuristic|slope"; "" for composites).
std::string whole_range_text(const storage::Setting& s);
std::string names_range_text(const storage::Setting& s);
std::string fixed_range_text(const storage::Setting& s, unsigned frac_bits);
template <typename T>
struct RangeText {
  static std::string of(const storage::Setting& s) {
    if (s.name_count > 0) return names_range_text(s);
    return whole_range_text(s);
  }
};
template <typename Rep, int F>
struct RangeText<Fixed<Rep, F>> {
  static std::string of(const storage::Setting& s) { return fixed_range_text(s, F); }
};
template <>
struct RangeText<Angle> {
  static std::string of(const storage::Setting& s) {
    return text_of_degrees(static_cast<uint32_t>(s.min)) + ".." +
           text_of_degrees(static_cast<uint32_t>(s.max));
  }
};
template <>
struct RangeText<hal::PipelineMapping> {
  static std::string of(const storage::Setting&) { return "W*H<=512"; }
};
template <>
struct RangeText<PreprocessConfig> {
  static std::string of(const storage::Setting&) {
    return "none|he|pn|igk|he-pn|igk-pn|igk-he";
  }
};
template <>
struct RangeText<OdometryConfig> {
  static std::string of(const storage::Setting&) { return ""; }
};
template <>
struct RangeText<storage::MapOrigin> {
  static std::string of(const storage::Setting&) { return ""; }
};
template <>
struct RangeText<storage::MapSize> {
  static std::string of(const storage::Setting& s) { return whole_range_text(s); }
};

// A decimal rounded to `frac_bits` fraction bits (ties away from zero) within [min, max].
// `format` names the Q format for messages ("UQ8.8").
std::string parse_fixed(const std::string& text, const storage::Setting& s, unsigned frac_bits,
                        const char* format, int64_t* raw);
template <typename Rep, int F>
std::string parse(const std::string& text, const storage::Setting& s, Fixed<Rep, F>* out) {
  constexpr bool kSigned = static_cast<Rep>(-1) < static_cast<Rep>(0);
  constexpr int kInteger = static_cast<int>(sizeof(Rep) * 8) - F - (kSigned ? 1 : 0);
  const std::string format =
      std::string(kSigned ? "Q" : "UQ") + std::to_string(kInteger) + "." + std::to_string(F);
  int64_t raw = 0;
  std::string error = parse_fixed(text, s, F, format.c_str(), &raw);
  if (error.empty()) *out = Fixed<Rep, F>::from_raw(static_cast<Rep>(raw));
  return error;
}

std::string text(uint8_t v, const storage::Setting& s);
std::string text(uint16_t v, const storage::Setting& s);
std::string text(uint32_t v, const storage::Setting& s);
std::string text(int32_t v, const storage::Setting& s);
std::string text(bool v, const storage::Setting& s);
std::string text(Angle v, const storage::Setting& s);
std::string text(storage::TriggerMode v, const storage::Setting& s);
std::string text(LocaliserMatcher v, const storage::Setting& s);
std::string text(const hal::PipelineMapping& v, const storage::Setting& s);
std::string text(const PreprocessConfig& v, const storage::Setting& s);
std::string text(const OdometryConfig& v, const storage::Setting& s);
std::string text(const storage::MapOrigin& v, const storage::Setting& s);
std::string text(const storage::MapSize& v, const storage::Setting& s);
std::string fixed_text(int64_t raw, unsigned frac_bits);
// A binary angle as the shortest decimal of degrees that reads back as it.
std::string text_of_degrees(uint32_t bam);
template <typename Rep, int F>
std::string text(Fixed<Rep, F> v, const storage::Setting&) {
  return fixed_text(static_cast<int64_t>(v.raw()), F);
}

// Whether the value has an option that writes it (a mapping that is a plain reduction, the
// default PN patches, odometry that differs only in the wheel constants).
template <typename T>
bool expressible(const T&) {
  return true;
}
bool expressible(const hal::PipelineMapping& v);
bool expressible(const PreprocessConfig& v);
bool expressible(const OdometryConfig& v);

// The option's placeholder in --help ("N", "X", "WxH", ...).
const char* type_name(const storage::Setting& s, const char* fallback);
template <typename T>
struct TypeName {
  static const char* of(const storage::Setting& s) { return type_name(s, "N"); }
};
template <typename Rep, int F>
struct TypeName<Fixed<Rep, F>> {
  static const char* of(const storage::Setting&) { return "X"; }
};
template <>
struct TypeName<Angle> {
  static const char* of(const storage::Setting&) { return "DEG"; }
};
template <>
struct TypeName<hal::PipelineMapping> {
  static const char* of(const storage::Setting&) { return "WxH"; }
};
template <>
struct TypeName<PreprocessConfig> {
  static const char* of(const storage::Setting&) { return "METHOD"; }
};
template <>
struct TypeName<OdometryConfig> {
  static const char* of(const storage::Setting&) { return "LEFT,RIGHT,TRACK"; }
};
template <>
struct TypeName<storage::MapOrigin> {
  static const char* of(const storage::Setting&) { return "X,Y"; }
};
template <>
struct TypeName<storage::MapSize> {
  static const char* of(const storage::Setting&) { return "WxH"; }
};

}  // namespace setting_text

// Why a setting of `scope` does nothing in run `c` ("" when it is used): e.g. the route
// search's settings with the heuristic matcher (config show).
std::string unused_note(uint16_t scope, const storage::RunConfig& c);

// ---------------------------------------------------------------------------------------
// The options of one subcommand, made from a settings table (RunSettings: the run
// configuration's; a test may extend it).

template <class Table = storage::RunSettings, class Config = storage::RunConfig>
class SettingOptions {
 public:
  // Which settings: those in `scopes`, without `except`; card_only: only those on the card.
  struct Selection {
    uint16_t scopes = 0xFFFF;
    std::vector<std::string> except;
    bool card_only = false;
  };

  // Registers --NAME for each selected setting on `app`, with the table's help, range and the
  // default of `defaults` ("Default X" in the help).
  void add(CLI::App* app, const Config& defaults, const Selection& selection) {
    Registrar r{this, app, selection};
    Table{}(r, defaults);
  }

  // The given options written into *config (CLI11 has validated each already).
  void apply(Config* config) const {
    Applier a{this};
    Table{}(a, *config);
  }

  // Whether --name was given on the command line.
  bool given(const std::string& name) const {
    const auto it = entries_.find(name);
    return it != entries_.end() && it->second->count() > 0;
  }
  // The option of setting `name` (null when not registered).
  CLI::Option* option(const std::string& name) const {
    const auto it = entries_.find(name);
    return it != entries_.end() ? it->second->option : nullptr;
  }

 private:
  struct Entry {
    std::string text;
    bool flag = false;
    CLI::Option* option = nullptr;
    size_t count() const { return option != nullptr ? option->count() : 0; }
  };

  static bool selected(const storage::Setting& s, const Selection& sel) {
    if ((s.scope & sel.scopes) == 0) return false;
    if (sel.card_only && s.since == storage::kPcOnly) return false;
    for (const std::string& e : sel.except) {
      if (e == s.name) return false;
    }
    return true;
  }

  struct Registrar {
    SettingOptions* self;
    CLI::App* app;
    const Selection& selection;
    template <class T>
    void operator()(const T& field, const storage::Setting& s) {
      if (!selected(s, selection)) return;
      auto entry = std::make_unique<Entry>();
      const std::string name = std::string("--") + s.name;
      std::string help = s.help != nullptr ? s.help : "";
      if constexpr (std::is_same_v<T, bool>) {
        entry->option = app->add_flag(name, entry->flag, help);
      } else {
        help += ". Default " + setting_text::text(field, s);
        const storage::Setting meta = s;
        entry->option = app->add_option(name, entry->text, help)
                            ->type_name(setting_text::TypeName<T>::of(s))
                            ->check(CLI::Validator(
                                [meta](std::string& text) {
                                  T probe{};
                                  return setting_text::parse(text, meta, &probe);
                                },
                                setting_text::RangeText<T>::of(s)));
      }
      self->entries_[s.name] = std::move(entry);
    }
    void pad(uint32_t) {}
  };

  struct Applier {
    const SettingOptions* self;
    template <class T>
    void operator()(T& field, const storage::Setting& s) const {
      const auto it = self->entries_.find(s.name);
      if (it == self->entries_.end() || it->second->count() == 0) return;
      if constexpr (std::is_same_v<T, bool>) {
        field = it->second->flag;
      } else {
        (void)setting_text::parse(it->second->text, s, &field);  // validated by CLI11
      }
    }
    void pad(uint32_t) {}
  };

  std::map<std::string, std::unique_ptr<Entry>> entries_;
};

// ---------------------------------------------------------------------------------------
// A parameter grid (seqslam sweep, transforms): several values of one setting.

namespace settings_cli_detail {

struct ListRegistrar {
  std::string name;
  CLI::App* app = nullptr;
  std::vector<std::string>* values = nullptr;
  CLI::Option* option = nullptr;
  template <class T>
  void operator()(const T&, const storage::Setting& s) {
    if (name != s.name) return;
    const storage::Setting meta = s;
    option = app->add_option(std::string("--") + s.name, *values,
                             std::string(s.help != nullptr ? s.help : "") +
                                 " (several, separated by commas: each is a point of the grid)")
                 ->delimiter(',')
                 ->type_name(setting_text::TypeName<T>::of(s))
                 ->check(CLI::Validator(
                     [meta](std::string& text) {
                       T probe{};
                       return setting_text::parse(text, meta, &probe);
                     },
                     setting_text::RangeText<T>::of(s)))
                 ->capture_default_str();
  }
  void pad(uint32_t) {}
};

struct Setter {
  const std::string& name;
  const std::string& text;
  std::string error = "no such setting";
  template <class T>
  void operator()(T& field, const storage::Setting& s) {
    if (name != s.name) return;
    if constexpr (std::is_same_v<T, bool>) {
      error = text == "yes" || text == "no" ? "" : "'" + text + "' is not yes or no";
      if (error.empty()) field = text == "yes";
    } else {
      error = setting_text::parse(text, s, &field);
    }
  }
  void pad(uint32_t) {}
};

}  // namespace settings_cli_detail

// Registers --NAME as a list of values of setting `name` (the table's help, its parse for each
// value) bound to `values`, whose current contents are the default.
template <class Table = storage::RunSettings, class Config = storage::RunConfig>
CLI::Option* add_setting_list(CLI::App* app, const std::string& name,
                              std::vector<std::string>* values) {
  settings_cli_detail::ListRegistrar r;
  r.name = name;
  r.app = app;
  r.values = values;
  const Config c{};
  Table{}(r, c);
  return r.option;
}

// Sets setting `name` of *config from its text: "" or what is wrong.
template <class Table = storage::RunSettings, class Config = storage::RunConfig>
std::string set_setting(Config* config, const std::string& name, const std::string& text) {
  settings_cli_detail::Setter v{name, text};
  Table{}(v, *config);
  return v.error;
}

// ---------------------------------------------------------------------------------------
// Printing a configuration.

struct SettingRow {
  std::string name;
  std::string value;  // with the unit
  std::string note;   // "(not used: ...)" or ""
};

namespace settings_cli_detail {

template <class Config>
struct Rows {
  const Config& config;
  std::vector<SettingRow> rows;
  template <class T>
  void operator()(const T& field, const storage::Setting& s) {
    if (s.since == storage::kPcOnly) return;
    SettingRow r;
    r.name = s.name;
    r.value = setting_text::text(field, s);
    if (s.unit != nullptr) r.value += std::string(" ") + s.unit;
    r.note = unused_note(s.scope, config);
    rows.push_back(r);
  }
  void pad(uint32_t) {}
};

struct Options {
  uint16_t scopes = 0;
  bool card_only = false;
  std::string text;
  bool expressible = true;
  template <class T>
  void operator()(const T& field, const storage::Setting& s) {
    if ((s.scope & scopes) == 0 || (card_only && s.since == storage::kPcOnly)) return;
    if (!setting_text::expressible(field)) expressible = false;
    if constexpr (std::is_same_v<T, bool>) {
      if (field) text += std::string(text.empty() ? "" : " ") + "--" + s.name;
    } else {
      text += std::string(text.empty() ? "" : " ") + "--" + s.name + " " +
              setting_text::text(field, s);
    }
  }
  void pad(uint32_t) {}
};

struct Value {
  const std::string& name;
  std::string text;
  template <class T>
  void operator()(const T& field, const storage::Setting& s) {
    if (name == s.name) text = setting_text::text(field, s);
  }
  void pad(uint32_t) {}
};

struct Find {
  int16_t want = 0;
  int16_t at = 0;
  std::string name;
  template <class T>
  void operator()(const T&, const storage::Setting& s) {
    if (at++ == want) name = s.name;
  }
  void pad(uint32_t) {}
};

}  // namespace settings_cli_detail

// One row per card setting of `config` (config show).
template <class Table = storage::RunSettings, class Config = storage::RunConfig>
std::vector<SettingRow> setting_rows(const Config& config) {
  settings_cli_detail::Rows<Config> r{config, {}};
  Table{}(r, config);
  return r.rows;
}

// The options that write `config`'s settings of `scopes` (card_only: those on the card), or
// "" when one of them has no option that writes its value (expressible()).
template <class Table = storage::RunSettings, class Config = storage::RunConfig>
std::string setting_options_text(const Config& config, uint16_t scopes, bool card_only) {
  settings_cli_detail::Options o;
  o.scopes = scopes;
  o.card_only = card_only;
  Table{}(o, config);
  return o.expressible ? o.text : std::string();
}

// The value of setting `name` of `config` as its option writes it ("" for no such setting).
template <class Table = storage::RunSettings, class Config = storage::RunConfig>
std::string setting_value_text(const Config& config, const std::string& name) {
  settings_cli_detail::Value v{name, {}};
  Table{}(v, config);
  return v.text;
}

// The name of the setting at `position` in the table (SettingsCheck::setting), or "".
template <class Table = storage::RunSettings, class Config = storage::RunConfig>
std::string setting_name(int16_t position) {
  settings_cli_detail::Find f;
  f.want = position;
  const Config c{};
  Table{}(f, c);
  return f.name;
}

}  // namespace seqslam::cli
