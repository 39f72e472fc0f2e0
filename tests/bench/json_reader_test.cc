// bench/io/json_reader: the JSON the harness writes, read back; errors name
// the source and the position.
#include "quasiroll/bench/io/json_reader.h"

#include <gtest/gtest.h>

#include <cmath>

#include "quasiroll/bench/io/json_writer.h"

namespace quasiroll {
namespace {

std::string ErrorOf(const std::string& text, const std::string& source = "") {
  try {
    ParseJson(text, source);
  } catch (const JsonError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(JsonReader, ReadsNestedObjectsAndArraysInOrder) {
  const JsonValue v = ParseJson(
      " {\"b\":{\"c\":[1,[true,false],{}],\"d\":[]},\"a\":null,"
      "\"s\":\"x,}\"} \n");
  ASSERT_TRUE(v.is_object());
  ASSERT_EQ(v.members().size(), 3u);
  EXPECT_EQ(v.members()[0].first, "b");  // file order, not sorted
  EXPECT_EQ(v.members()[1].first, "a");
  EXPECT_TRUE(v.Find("a")->is_null());
  EXPECT_EQ(v.Find("s")->str(), "x,}");
  EXPECT_EQ(v.Find("missing"), nullptr);
  const JsonValue& c = *v.Find("b")->Find("c");
  ASSERT_EQ(c.items().size(), 3u);
  EXPECT_EQ(c.items()[0].number(), 1.0);
  EXPECT_TRUE(c.items()[1].items()[0].boolean());
  EXPECT_FALSE(c.items()[1].items()[1].boolean());
  EXPECT_TRUE(c.items()[2].members().empty());
  EXPECT_TRUE(v.Find("b")->Find("d")->items().empty());
  // Raw texts are the bytes as written, spacing included.
  EXPECT_EQ(v.Find("b")->raw(), "{\"c\":[1,[true,false],{}],\"d\":[]}");
  EXPECT_EQ(v.Find("s")->raw(), "\"x,}\"");
  EXPECT_EQ(ParseJson("{ \"k\" : [ 1 , 2 ] }").Find("k")->raw(), "[ 1 , 2 ]");
}

TEST(JsonReader, DecodesEscapes) {
  const JsonValue v = ParseJson(
      R"(["q\"b\\s\/n\nt\tr\rb\bf\f", "\u00e9\u20ac\ud83d\ude00\u0001A"])");
  EXPECT_EQ(v.items()[0].str(), "q\"b\\s/n\nt\tr\rb\bf\f");
  EXPECT_EQ(v.items()[1].str(),
            "\xc3\xa9\xe2\x82\xac\xf0\x9f\x98\x80\x01"
            "A");
  EXPECT_EQ(v.items()[0].raw(), R"("q\"b\\s\/n\nt\tr\rb\bf\f")");
}

TEST(JsonReader, ReadsNumbersAsStrtodDoes) {
  const JsonValue v =
      ParseJson("[0,-0,-1.5e3,2E-2,1e+20,0.1,123456789012,-0.25]");
  const std::vector<double> want = {0,    -0.0, -1500,          0.02,
                                    1e20, 0.1,  123456789012.0, -0.25};
  ASSERT_EQ(v.items().size(), want.size());
  for (std::size_t k = 0; k < want.size(); ++k)
    EXPECT_EQ(v.items()[k].number(), want[k]) << k;
  EXPECT_TRUE(std::signbit(v.items()[1].number()));
  EXPECT_EQ(v.items()[2].raw(), "-1.5e3");
}

TEST(JsonReader, ReadsWhatJsonWriterWrites) {
  JsonWriter w;
  w.BeginObject();
  w.Key("x").Value(0.1 + 0.2);
  w.Key("nan").Value(std::nan(""));
  w.Key("text").Value(std::string("a\"b\\c\nd\te\x01"));
  w.Key("list").BeginArray().Value(1).Value(true).EndArray();
  w.EndObject();
  const JsonValue v = ParseJson(w.str());
  EXPECT_EQ(v.Find("x")->number(), 0.1 + 0.2);  // bit for bit
  EXPECT_TRUE(v.Find("nan")->is_null());
  EXPECT_EQ(v.Find("text")->str(), "a\"b\\c\nd\te\x01");
  EXPECT_EQ(v.Find("list")->items().size(), 2u);
  EXPECT_EQ(v.raw(), w.str());
}

TEST(JsonReader, RejectsMalformedTextNamingSourceAndPosition) {
  EXPECT_EQ(ErrorOf("{\"a\":1", "dir/meta.json"),
            "dir/meta.json: malformed JSON at line 1, column 7: ',' or '}' "
            "expected");
  EXPECT_EQ(ErrorOf("{\n  \"a\": tru\n}"),
            "malformed JSON at line 2, column 8: value expected");
  for (const char* bad : {"",
                          "{",
                          "[1,]",
                          "{\"a\" 1}",
                          "{a:1}",
                          "[1 2]",
                          "\"open",
                          "01",
                          "-",
                          "1.",
                          "1e",
                          "+1",
                          ".5",
                          "nul",
                          "[\"\\x\"]",
                          "[\"\\u12g4\"]",
                          "[\"\\ud800\"]",
                          "[\"\\udc00\"]",
                          "\"tab\there\"",
                          "{} {}",
                          "[1]]"}) {
    const std::string e = ErrorOf(bad, "f.json");
    EXPECT_EQ(e.rfind("f.json: malformed JSON at line ", 0), 0u)
        << bad << " -> " << e;
  }
  EXPECT_NE(ErrorOf("\"abc").find("unterminated string"), std::string::npos);
  EXPECT_NE(ErrorOf(std::string(300, '[')).find("nested too deeply"),
            std::string::npos);
}

TEST(JsonReader, WrongTypeAccessThrows) {
  const JsonValue v = ParseJson("{\"n\":1,\"s\":\"x\"}");
  EXPECT_THROW(v.Find("n")->str(), JsonError);
  EXPECT_THROW(v.Find("s")->number(), JsonError);
  EXPECT_THROW(v.items(), JsonError);
  EXPECT_THROW(v.Find("s")->boolean(), JsonError);
  EXPECT_EQ(v.Find("n")->Find("x"), nullptr);  // not an object: no member
}

}  // namespace
}  // namespace quasiroll
