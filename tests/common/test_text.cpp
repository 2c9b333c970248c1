// Names that become paths or plot strings, and message text that reaches a terminal.
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "jointsim/common/text.hpp"

using jointsim::firstInvalidUtf8;
using ::testing::EndsWith;
using ::testing::HasSubstr;
using ::testing::Not;
using ::testing::StartsWith;

TEST(SafeName, AcceptsIdentifiersAndRejectsPathsAndControlCharacters) {
  for (const std::string& good : std::vector<std::string>{"ur5_fall", "run-01", "a.b", "X", std::string(128, 'n')})
    EXPECT_TRUE(jointsim::isSafeName(good)) << good;
  for (const std::string& bad :
       std::vector<std::string>{"", ".", "..", ".hidden", "-rf", "a/b", "a\\b", "../x", "pw\nsystem(\"touch X\")\n#",
                                "a b", "a'b", "j6/x", "é", std::string(129, 'n'), std::string("a\0b", 3)})
    EXPECT_FALSE(jointsim::isSafeName(bad)) << jointsim::printable(bad);
  EXPECT_EQ(jointsim::safeFileName("../j6/x"), "_._j6_x");
  EXPECT_EQ(jointsim::safeFileName(""), "_");
  EXPECT_TRUE(jointsim::isSafeName(jointsim::safeFileName("..")));
}

TEST(Printable, EscapesControlBytesOnOneLine) {
  EXPECT_EQ(jointsim::printable("a\nb\tc\rd\x1b[31me\x7f"), "a\\nb\\tc\\rd\\x1b[31me\\x7f");
  EXPECT_EQ(jointsim::printable("plain text"), "plain text");
}

TEST(Printable, CutsTheMiddleKeepingTheReasonAtTheEnd) {
  const std::string message = "/tmp/" + std::string(10'000'000, 'a') +  // tmp-path-ok: message text, never a file
                              ": cannot create directory: File name too long";
  const std::string p = jointsim::printable(message, 2000);
  EXPECT_LE(p.size(), 2100u);
  EXPECT_THAT(p, StartsWith("/tmp/aaa"));  // tmp-path-ok: message text, never a file
  EXPECT_THAT(p, EndsWith(": cannot create directory: File name too long"));
  EXPECT_THAT(p, HasSubstr(" bytes cut) ..."));
  EXPECT_THAT(p, Not(HasSubstr("\n")));
}

TEST(Printable, NeverSplitsAUtf8Sequence) {
  // "é" is two bytes (C3 A9); the cut must fall between characters at any budget.
  std::string text;
  for (int i = 0; i < 500; ++i) text += "é";
  for (size_t budget : {10u, 11u, 12u, 99u, 100u, 101u}) {
    const std::string p = jointsim::printable(text, budget);
    const size_t cut = p.find("... (");
    ASSERT_NE(cut, std::string::npos);
    const std::string head = p.substr(0, cut), tail = p.substr(p.find(") ...") + 5);
    EXPECT_EQ(head.size() % 2, 0u) << budget;
    EXPECT_EQ(tail.size() % 2, 0u) << budget;
    EXPECT_EQ(head.find_first_not_of("\xC3\xA9"), std::string::npos);
    EXPECT_TRUE(head.empty() || static_cast<unsigned char>(head[0]) == 0xC3);
    EXPECT_TRUE(tail.empty() || static_cast<unsigned char>(tail[0]) == 0xC3);
  }
}

// Against the well-formed byte sequences of Unicode (table 3-7) and the classic malformed cases.
TEST(Utf8, FirstInvalidByteOfMalformedSequences) {
  constexpr size_t kOk = std::string::npos;
  EXPECT_EQ(firstInvalidUtf8(""), kOk);
  EXPECT_EQ(firstInvalidUtf8("plain ascii\n"), kOk);
  EXPECT_EQ(firstInvalidUtf8("N\xC2\xB7m \xE2\x80\x93 \xF0\x9F\x98\x80"), kOk);  // N·m – 😀
  EXPECT_EQ(firstInvalidUtf8("\xEF\xBF\xBD\xF4\x8F\xBF\xBF"), kOk);              // U+FFFD, U+10FFFF
  EXPECT_EQ(firstInvalidUtf8("ab\xC4"), 2u);                                     // lead byte at the end
  EXPECT_EQ(firstInvalidUtf8("ab\xE2\x80"), 2u);                                 // cut 3-byte sequence
  EXPECT_EQ(firstInvalidUtf8("a\x80"), 1u);                                      // lone continuation byte
  EXPECT_EQ(firstInvalidUtf8("a\xC0\xAF"), 1u);                                  // overlong '/'
  EXPECT_EQ(firstInvalidUtf8("a\xE0\x80\xAF"), 1u);                              // overlong, 3 bytes
  EXPECT_EQ(firstInvalidUtf8("a\xED\xA0\x80"), 1u);                              // surrogate U+D800
  EXPECT_EQ(firstInvalidUtf8("a\xF4\x90\x80\x80"), 1u);                          // above U+10FFFF
  EXPECT_EQ(firstInvalidUtf8("a\xF8\x88\x80\x80\x80"), 1u);                      // 5-byte form
  EXPECT_EQ(firstInvalidUtf8("\xC3\xA9t\xC3"), 3u);                              // é then a cut one
}
