#include "core/doe/word.hpp"

#include <cctype>

#include "core/common/error.hpp"

namespace demcal::doe {

namespace {
constexpr std::string_view kLetters = "ABCDEFGHJKLMNOPQRSTUVWXYZ";
}  // namespace

char factor_letter(int index) {
  if (index < 0 || index >= kMaxFactors) {
    throw InputError("factor", "index " + std::to_string(index) + " has no letter (at most " +
                                   std::to_string(kMaxFactors) + " factors)");
  }
  return kLetters[static_cast<std::size_t>(index)];
}

int factor_index(char letter) {
  const auto pos =
      kLetters.find(static_cast<char>(std::toupper(static_cast<unsigned char>(letter))));
  return pos == std::string_view::npos ? -1 : static_cast<int>(pos);
}

std::string word_name(Word w) {
  if (w == 0) return "I";
  std::string name;
  for (int i = 0; i < kMaxFactors; ++i) {
    if (w & (Word{1} << i)) name += factor_letter(i);
  }
  return name;
}

std::string word_name(const SignedWord& w) {
  std::string name = w.sign < 0 ? "-" : "";
  name += word_name(w.word);
  return name;
}

Word parse_word(std::string_view text, const std::string& where) {
  if (text.empty()) throw InputError(where, "empty effect word");
  Word w = 0;
  for (const char c : text) {
    const int i = factor_index(c);
    if (i < 0) {
      throw InputError(where, std::string("'") + c + "' in '" + std::string(text) +
                                  "' is not a factor letter (A-Z without I)");
    }
    const Word bit = Word{1} << i;
    if (w & bit) {
      throw InputError(where,
                       std::string("letter '") + c + "' repeated in '" + std::string(text) + "'");
    }
    w |= bit;
  }
  return w;
}

std::string chain_name(const std::vector<SignedWord>& chain) {
  std::string name;
  for (std::size_t i = 0; i < chain.size(); ++i) {
    if (i > 0) name += '=';
    name += word_name(chain[i]);
  }
  return name;
}

}  // namespace demcal::doe
