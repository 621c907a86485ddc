// Program text made printable: see printable_text.hpp.
#include "harness/printable_text.hpp"

#include <cstddef>

namespace cb {

namespace {

/// Length of the escape sequence starting at s[i] == ESC (at least 1).
size_t escape_length(const std::string& s, size_t i)
{
    const size_t n = s.size();
    if (i + 1 >= n) return 1;
    const unsigned char kind = static_cast<unsigned char>(s[i + 1]);
    if (kind == '[') {  // CSI: parameters and intermediates, then a final byte 0x40..0x7E
        size_t j = i + 2;
        while (j < n && !(s[j] >= 0x40 && s[j] <= 0x7E)) ++j;
        return (j < n ? j + 1 : n) - i;
    }
    if (kind == ']' || kind == 'P' || kind == 'X' || kind == '^' || kind == '_') {  // string: to BEL or ESC '\'
        size_t j = i + 2;
        while (j < n && s[j] != '\a' && !(s[j] == '\x1b' && j + 1 < n && s[j + 1] == '\\')) ++j;
        if (j >= n) return n - i;
        return (s[j] == '\a' ? j + 1 : j + 2) - i;
    }
    return 2;  // ESC and one character (charset selection, reset, ...)
}

/// Length of the valid UTF-8 sequence at s[i] (a lead byte >= 0x80), or 0 when invalid; its
/// code point in `cp`.
size_t utf8_length(const std::string& s, size_t i, unsigned& cp)
{
    const unsigned char c = static_cast<unsigned char>(s[i]);
    // The lead byte gives the length, its payload bits and the smallest code point of that length.
    const size_t len = c >= 0xF0 ? 4 : c >= 0xE0 ? 3 : 2;
    const unsigned min = len == 4 ? 0x10000 : len == 3 ? 0x800 : 0x80;
    if (c < 0xC2 || c > 0xF4) return 0;
    cp = c & (len == 4 ? 0x07 : len == 3 ? 0x0F : 0x1F);
    if (i + len > s.size()) return 0;
    for (size_t k = 1; k < len; ++k) {
        const unsigned char d = static_cast<unsigned char>(s[i + k]);
        if ((d & 0xC0) != 0x80) return 0;
        cp = (cp << 6) | (d & 0x3F);
    }
    if (cp < min || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return 0;
    return len;
}

}  // namespace

std::string printable_text(const std::string& raw)
{
    std::string out;
    out.reserve(raw.size());
    for (size_t i = 0; i < raw.size();) {
        const unsigned char c = static_cast<unsigned char>(raw[i]);
        if (c == 0x1B) {
            i += escape_length(raw, i);
        } else if (c == '\n' || c == '\t') {
            out += raw[i++];
        } else if (c < 0x20 || c == 0x7F) {
            out += ' ';
            ++i;
        } else if (c < 0x80) {
            out += raw[i++];
        } else if (unsigned cp = 0; const size_t len = utf8_length(raw, i, cp)) {
            if (cp <= 0x9F)
                out += '?';  // a C1 control (U+009B is a CSI on some terminals)
            else
                out.append(raw, i, len);
            i += len;
        } else {
            out += '?';
            ++i;
        }
    }
    return out;
}

}  // namespace cb
