// Every value rule of FORMAT.md "Validation": a trace with one defect, written by the
// spec encoder, is rejected by the reader at the defective field; validate() rejects the
// same trace in memory with the same words; encode() refuses to write it.
#include <gtest/gtest.h>

#include <functional>
#include <limits>

#include "expect_format_error.h"
#include "trace_test_support.h"

namespace tilevis::trace {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

struct RuleCase {
  std::string name;
  std::function<void(Trace&)> inject;
  std::string field;     // spec encoder key of the reported field
  uint64_t within = 0;   // bytes into that field (UTF-8: the malformed sequence)
  std::string fragment;  // expected in the message
};

void PrintTo(const RuleCase& rule, std::ostream* os) { *os << rule.name; }

Frame& f1(Trace& t) { return t.frames[1]; }
Draw& screen(Trace& t) { return t.frames[1].draws[1]; }

std::vector<RuleCase> rule_cases() {
  return {
      {"ZeroFrames", [](Trace& t) { t.frames.clear(); }, "frame_count", 0, "frame count 0, expected at least 1"},
      {"SourceTooLong", [](Trace& t) { t.source.assign(kMaxSourceBytes + 1, 's'); }, "source_length", 0,
       "source length 65537, expected at most 65536"},
      {"SourceNotUtf8", [](Trace& t) { t.source = "scene\xFF.json"; }, "source", 5,
       "source byte 5 breaks UTF-8, expected well-formed UTF-8"},
      {"WidthZero", [](Trace& t) { f1(t).width = 0; }, "f1.width", 0, "frame 1: width 0, expected 1..16384"},
      {"WidthTooLarge", [](Trace& t) { f1(t).width = kMaxViewport + 1; }, "f1.width", 0,
       "frame 1: width 16385, expected 1..16384"},
      {"HeightZero", [](Trace& t) { f1(t).height = 0; }, "f1.height", 0, "frame 1: height 0, expected 1..16384"},
      {"HeightTooLarge", [](Trace& t) { f1(t).height = 0xFFFFFFFFu; }, "f1.height", 0,
       "frame 1: height 4294967295, expected 1..16384"},
      {"DepthNearNaN", [](Trace& t) { f1(t).depth_near = kNaN; }, "f1.depth_near", 0,
       "frame 1: depth_near nan, expected a value in [0, 1]"},
      {"DepthNearNegative", [](Trace& t) { f1(t).depth_near = -0.5f; }, "f1.depth_near", 0,
       "frame 1: depth_near -0.5, expected a value in [0, 1]"},
      {"DepthFarAboveOne", [](Trace& t) { f1(t).depth_far = 1.5f; }, "f1.depth_far", 0,
       "frame 1: depth_far 1.5, expected a value in [0, 1]"},
      {"DepthFarInf", [](Trace& t) { f1(t).depth_far = kInf; }, "f1.depth_far", 0,
       "frame 1: depth_far inf, expected a value in [0, 1]"},
      {"SubpixelBitsTooMany", [](Trace& t) { f1(t).subpixel_bits = kMaxSubpixelBits + 1; }, "f1.subpixel_bits", 0,
       "frame 1: subpixel bits 9, expected 1..8"},
      {"SubpixelBitsZero", [](Trace& t) { f1(t).subpixel_bits = 0; }, "f1.subpixel_bits", 0,
       "frame 1: subpixel bits 0, expected 1..8"},
      {"SampleCountThree", [](Trace& t) { f1(t).samples.resize(3); }, "f1.sample_count", 0,
       "frame 1: sample count 3, expected 1, 2, 4, 8 or 16"},
      {"SampleCountZero", [](Trace& t) { f1(t).samples.clear(); }, "f1.sample_count", 0,
       "frame 1: sample count 0, expected 1, 2, 4, 8 or 16"},
      {"SampleCountThirtyTwo", [](Trace& t) { f1(t).samples.resize(32); }, "f1.sample_count", 0,
       "frame 1: sample count 32, expected 1, 2, 4, 8 or 16"},
      {"SampleXOutsidePixel", [](Trace& t) { f1(t).samples[5].x = 16; }, "f1.s5.x", 0,
       "frame 1: sample 5 x 16, expected < 16 (2^subpixel bits)"},
      {"SampleYOutsidePixel", [](Trace& t) { f1(t).samples[15].y = 0xFFFF; }, "f1.s15.y", 0,
       "frame 1: sample 15 y 65535, expected < 16 (2^subpixel bits)"},
      {"NameTooLong", [](Trace& t) { screen(t).name.assign(kMaxNameBytes + 1, 'n'); }, "f1.d1.name_length", 0,
       "frame 1, draw 1: name length 4097, expected at most 4096"},
      {"NameStrayContinuationByte", [](Trace& t) { screen(t).name = "ab\x80"; }, "f1.d1.name", 2,
       "frame 1, draw 1: name byte 2 breaks UTF-8"},
      {"NameCutSequence", [](Trace& t) { screen(t).name = "abc\xE2\x9C"; }, "f1.d1.name", 3,
       "frame 1, draw 1: name byte 3 breaks UTF-8"},
      {"NameOverlong", [](Trace& t) { screen(t).name = "\xC0\xAF"; }, "f1.d1.name", 0,
       "frame 1, draw 1: name byte 0 breaks UTF-8"},
      {"NameSurrogate", [](Trace& t) { screen(t).name = "x\xED\xA0\x80"; }, "f1.d1.name", 1,
       "frame 1, draw 1: name byte 1 breaks UTF-8"},
      {"NameAboveUnicode", [](Trace& t) { screen(t).name = "xy\xF4\x90\x80\x80"; }, "f1.d1.name", 2,
       "frame 1, draw 1: name byte 2 breaks UTF-8"},
      {"UnknownFlagBit", [](Trace& t) { screen(t).flags = kKnownDrawFlags + 1; }, "f1.d1.flags", 0,
       "frame 1, draw 1: flags 0x40 set unknown bits 0x40, expected only bits of 0x"},
      {"UnknownHighFlagBit", [](Trace& t) { screen(t).flags = 0x80000001u; }, "f1.d1.flags", 0,
       "flags 0x80000001 set unknown bits 0x80000000"},
      {"ShaderCostNegative", [](Trace& t) { screen(t).shader_cycles_per_fragment = -1.0f; }, "f1.d1.shader_cost", 0,
       "frame 1, draw 1: shader cycles per fragment -1, expected a finite value >= 0"},
      {"ShaderCostNaN", [](Trace& t) { screen(t).shader_cycles_per_fragment = kNaN; }, "f1.d1.shader_cost", 0,
       "shader cycles per fragment nan, expected a finite value >= 0"},
      {"ShaderCostInf", [](Trace& t) { screen(t).shader_cycles_per_fragment = kInf; }, "f1.d1.shader_cost", 0,
       "shader cycles per fragment inf, expected a finite value >= 0"},
      {"IndexCountNotMultipleOfThree", [](Trace& t) { screen(t).indices.push_back(0); }, "f1.d1.index_count", 0,
       "frame 1, draw 1: index count 4, expected a multiple of 3"},
      {"VertexNaN", [](Trace& t) { screen(t).vertices[2].w = kNaN; }, "f1.d1.v2.w", 0,
       "frame 1, draw 1: vertex 2 w nan, expected a finite float"},
      {"VertexMinusInf", [](Trace& t) { screen(t).vertices[1].x = -kInf; }, "f1.d1.v1.x", 0,
       "frame 1, draw 1: vertex 1 x -inf, expected a finite float"},
      {"IndexNotBelowVertexCount", [](Trace& t) { screen(t).indices[2] = 3; }, "f1.d1.i2", 0,
       "frame 1, draw 1: index 3 >= vertex count 3 (indices[2])"},
      {"IndexMaxValue", [](Trace& t) { screen(t).indices[0] = 0xFFFFFFFFu; }, "f1.d1.i0", 0,
       "index 4294967295 >= vertex count 3 (indices[0])"},
      {"IndexIntoEmptyDraw", [](Trace& t) { t.frames[1].draws[2].indices = {0, 0, 0}; }, "f1.d2.i0", 0,
       "frame 1, draw 2: index 0 >= vertex count 0 (indices[0])"},
      {"DefectInFirstFrame", [](Trace& t) { t.frames[0].draws[1].indices[1] = 7; }, "f0.d1.i1", 0,
       "frame 0, draw 1: index 7 >= vertex count 3 (indices[1])"},
  };
}

class ValueRule : public ::testing::TestWithParam<RuleCase> {};

TEST_P(ValueRule, ReaderRejectsAtTheField) {
  Trace trace = test::multi_frame_trace();
  GetParam().inject(trace);
  const test::SpecFile file = test::spec_encode(trace);
  test::expect_rejected(file.bytes, file.at(GetParam().field) + GetParam().within, GetParam().fragment);
}

TEST_P(ValueRule, ValidateRejectsWithTheReadersWords) {
  Trace trace = test::multi_frame_trace();
  GetParam().inject(trace);
  const test::SpecFile file = test::spec_encode(trace);
  const std::string reader_says =
      test::expect_rejected(file.bytes, file.at(GetParam().field) + GetParam().within, GetParam().fragment);
  try {
    validate(trace, "scene.json");
    FAIL() << "validate accepted: " << GetParam().fragment;
  } catch (const FormatError& e) {
    EXPECT_EQ(test::check_format_error(e, "scene.json", 0, GetParam().fragment), reader_says);
  }
}

TEST_P(ValueRule, EncodeRefuses) {
  Trace trace = test::multi_frame_trace();
  GetParam().inject(trace);
  EXPECT_THROW(encode(trace), FormatError);
}

INSTANTIATE_TEST_SUITE_P(TraceReject, ValueRule, ::testing::ValuesIn(rule_cases()),
                         [](const ::testing::TestParamInfo<RuleCase>& rule) { return rule.param.name; });

TEST(TraceValidate, AcceptsTheSeeds) {
  EXPECT_NO_THROW(validate(test::triangle_trace()));
  EXPECT_NO_THROW(validate(test::multi_frame_trace()));
  EXPECT_NO_THROW(validate(test::grid_trace(3)));
}

TEST(TraceValidate, AcceptsWellFormedUtf8AtTheEdges) {
  Trace trace = test::triangle_trace();
  for (const char* name : {"", "\x7F", "\xC2\x80", "\xDF\xBF", "\xE0\xA0\x80", "\xED\x9F\xBF", "\xEE\x80\x80",
                           "\xEF\xBF\xBF", "\xF0\x90\x80\x80", "\xF4\x8F\xBF\xBF"}) {
    trace.frames[0].draws[0].name = name;
    EXPECT_NO_THROW(validate(trace)) << "name bytes: " << ::testing::PrintToString(std::string(name));
    const std::vector<uint8_t> bytes = encode(trace);
    EXPECT_EQ(decode(bytes.data(), bytes.size()), trace);
  }
}

TEST(TraceValidate, AcceptsTheLimitsThemselves) {
  Trace trace = test::triangle_trace();
  Frame& frame = trace.frames[0];
  frame.width = kMaxViewport;
  frame.height = 1;
  frame.depth_near = 1.0f;
  frame.depth_far = 0.0f;
  frame.subpixel_bits = kMaxSubpixelBits;
  frame.samples = {{255, 0}, {0, 255}};
  Draw& draw = frame.draws[0];
  draw.name.assign(kMaxNameBytes, 'n');
  draw.flags = kKnownDrawFlags;
  draw.shader_cycles_per_fragment = 0.0f;
  draw.vertices[0] = {std::numeric_limits<float>::max(), std::numeric_limits<float>::lowest(),
                      std::numeric_limits<float>::denorm_min(), -0.0f};
  trace.source.assign(kMaxSourceBytes, 's');
  EXPECT_NO_THROW(validate(trace));
  const std::vector<uint8_t> bytes = encode(trace);
  EXPECT_EQ(decode(bytes.data(), bytes.size()), trace);
}

}  // namespace
}  // namespace tilevis::trace
