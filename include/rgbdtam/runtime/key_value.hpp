#pragma once
// Human-editable `key = value` files (# comments) read against one schema table: each key's
// type, range, unit and meaning, used to validate, print and document. Params (config/) and
// board definitions (board/) both use it. Errors name the file, the line and the key.

#include <cstddef>
#include <cstdint>

#include "rgbdtam/core/status.hpp"

namespace rgbdtam {

enum class ValueType {
  kReal,              // double
  kFloat,             // float
  kInt,               // int, whole numbers only
  kBool,              // true/false/1/0
  kMillisecondsAsNs,  // written in ms, stored as int64_t ns
  kDegreesAsRadians,  // written in degrees, stored as double radians
  kText,              // char[kTextBytes]
  kCustom,            // parsed and printed by the spec's own functions
};

constexpr int kTextBytes = 128;

struct KeySpec {
  const char* key;
  ValueType type;
  double min, max;  // numbers only
  const char* unit;
  const char* doc;
  void* (*field)(void* target);
  bool required;
  // kCustom only: false when value is not valid (error names the key and doc).
  bool (*parse)(const char* value, void* field) = nullptr;
  void (*print)(const void* field, char* out, size_t size) = nullptr;
};

struct KeyTable {
  const KeySpec* specs;
  int count;
};

// Parses a whole file's text into target. seen (count entries) records the keys found; a
// required key that is missing is an error. target is left partly written on error.
Status parse_key_values(const char* text, const char* source, const KeyTable& table, void* target);
// Applies one `key=value` assignment (e.g. a command-line override).
Status apply_key_value(const char* assignment, const char* source, const KeyTable& table,
                       void* target);
// How print_key_values lists the keys: as lines a file of this schema takes back
// (`key = value  # meaning, unit`), or as the rows of a Markdown table (key, value, unit, range,
// meaning) under its header, for the generated docs/configuration.md.
enum class KeyListing { kFile, kMarkdown };
// Writes every key with its current value, unit and meaning, one per line.
void print_key_values(const KeyTable& table, void* target, char* buf, int size,
                      KeyListing listing = KeyListing::kFile);

// kCustom functions for an SE3 written `qw qx qy qz tx ty tz` (a unit quaternion, metres each
// within 10).
bool parse_pose_value(const char* value, void* field);
void print_pose_value(const void* field, char* out, size_t size);

}  // namespace rgbdtam
