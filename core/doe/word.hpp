#pragma once
// Effects of a two-level design as bit masks: bit i set = factor i takes part. A main effect
// has one bit, a two-factor interaction (2FI) two, a defining word as many as its length.
// Letters follow FrF2 (Groemping 2014): A, B, ..., skipping I, so that output can be compared
// with tests/data/doe-oracle/ letter for letter.
#include <bit>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace demcal::doe {

using Word = std::uint32_t;

/// The most factors a two-level design may have: one letter each in "A..Z without I".
inline constexpr int kMaxFactors = 25;

inline int word_length(Word w) {
  return std::popcount(w);
}

/// A word with the sign it carries in a defining relation or an alias chain (I = -ABCF).
struct SignedWord {
  Word word = 0;
  int sign = 1;
  bool operator==(const SignedWord&) const = default;
};

/// Letter of factor `index` (0-based): A, B, ..., H, J, ... (no I).
char factor_letter(int index);
/// Factor index of a letter, or -1 when it is not a factor letter.
int factor_index(char letter);
/// "ABCF" for the word, "I" for the empty word.
std::string word_name(Word w);
/// "-ABCF" when sign is negative.
std::string word_name(const SignedWord& w);
/// Parses "ABCF" (letters only, no repeats); `where` names the argument in errors.
Word parse_word(std::string_view text, const std::string& where);
/// "AB=CF=-DG": the members of a chain joined by '='.
std::string chain_name(const std::vector<SignedWord>& chain);

}  // namespace demcal::doe
