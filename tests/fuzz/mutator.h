// A deterministic mutation driver for the parsers of outside input (GCC has no libFuzzer): seeded
// byte flips, byte sets, insertions of random bytes and of format tokens, deletions, truncations,
// duplications and splices with other corpus entries, stacked 1-4 per execution. The same seed gives
// the same sequence of inputs, so a failure found in CI is found again on any machine.
#pragma once
#include <algorithm>
#include <cctype>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

namespace rsvio::fuzz {

class Mutator {
 public:
  Mutator(uint64_t seed, std::vector<std::string> corpus, std::vector<std::string> tokens)
      : rng_(seed), corpus_(std::move(corpus)), tokens_(std::move(tokens)) {
    if (corpus_.empty()) corpus_.push_back("");
    // Tokens every text format reacts to.
    for (const char* t : {"\n", "\r\n", ",", " ", "#", "0", "-1", "nan", "inf", "-inf", "1e309", "-0",
                          "9223372036854775807", "-9223372036854775808", "18446744073709551616", "\t", "\"", "\0",
                          "\xef\xbb\xbf", "\xff"})
      tokens_.emplace_back(t, t[0] == '\0' ? 1 : std::char_traits<char>::length(t));
  }

  // The next input: a corpus entry with 1-4 stacked mutations.
  std::string next() {
    std::string s = corpus_[pick(corpus_.size())];
    const int n = 1 + static_cast<int>(pick(4));
    for (int k = 0; k < n; ++k) mutate(s);
    if (s.size() > kMaxSize) s.resize(kMaxSize);
    return s;
  }

  static constexpr size_t kMaxSize = 1 << 16;

 private:
  size_t pick(size_t n) { return n == 0 ? 0 : std::uniform_int_distribution<size_t>(0, n - 1)(rng_); }
  char byte() { return static_cast<char>(pick(256)); }

  // A position anywhere in s, ends included.
  size_t pos(const std::string& s) { return pick(s.size() + 1); }

  void mutate(std::string& s) {
    switch (pick(11)) {
      case 0:  // flip one bit
        if (!s.empty()) s[pick(s.size())] ^= static_cast<char>(1 << pick(8));
        break;
      case 1:  // set one byte
        if (!s.empty()) s[pick(s.size())] = byte();
        break;
      case 2: {  // insert random bytes
        const size_t n = 1 + pick(8);
        std::string b;
        for (size_t i = 0; i < n; ++i) b += byte();
        s.insert(pos(s), b);
        break;
      }
      case 3:
      case 4:  // insert a token
        s.insert(pos(s), tokens_[pick(tokens_.size())]);
        break;
      case 5: {  // replace a number-like run by a token
        if (s.empty()) break;
        size_t a = pick(s.size()), b = a;
        while (b < s.size() && (std::isalnum(static_cast<unsigned char>(s[b])) || s[b] == '.' || s[b] == '-')) ++b;
        s.replace(a, b - a, tokens_[pick(tokens_.size())]);
        break;
      }
      case 6: {  // delete a range
        if (s.empty()) break;
        const size_t a = pick(s.size());
        s.erase(a, 1 + pick(std::min<size_t>(s.size() - a, 32)));
        break;
      }
      case 7:  // truncate
        s.resize(pick(s.size() + 1));
        break;
      case 8: {  // duplicate a range (repeated lines, nested brackets)
        if (s.empty()) break;
        const size_t a = pick(s.size());
        const std::string part = s.substr(a, 1 + pick(std::min<size_t>(s.size() - a, 64)));
        s.insert(pos(s), part);
        break;
      }
      case 9: {  // splice: head of this one, tail of another
        const std::string& o = corpus_[pick(corpus_.size())];
        s = s.substr(0, pos(s)) + o.substr(pick(o.size() + 1));
        break;
      }
      default: {  // swap two lines
        std::vector<std::string> lines;
        size_t start = 0;
        for (size_t i = 0; i <= s.size(); ++i)
          if (i == s.size() || s[i] == '\n') {
            lines.push_back(s.substr(start, i - start));
            start = i + 1;
          }
        if (lines.size() < 2) break;
        std::swap(lines[pick(lines.size())], lines[pick(lines.size())]);
        s.clear();
        for (size_t i = 0; i < lines.size(); ++i) s += (i ? "\n" : "") + lines[i];
        break;
      }
    }
  }

  std::mt19937_64 rng_;
  std::vector<std::string> corpus_;
  std::vector<std::string> tokens_;
};

}  // namespace rsvio::fuzz
