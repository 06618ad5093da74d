// ConeLOD — version 8's position coder: an adaptive binary range coder (LZMA's: 32-bit range,
// 11-bit probabilities) and the model that codes a unit's position residuals with it. The writer
// (lod_writer.cpp) encodes, the reader (lod_reader.cpp) decodes, and web/clod.js decodes the same
// bytes with the same arithmetic; lod_format.md ("Coded positions") describes the stream.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdlib>
#include <cstdint>
#include <vector>

namespace conelod {
namespace lodfile {

constexpr int kRangeProbBits = 11;  // a probability of a 0 in 1/2048
constexpr uint16_t kRangeProbHalf = 1u << (kRangeProbBits - 1);
constexpr int kRangeAdaptShift = 4;       // each bit moves it 1/16 of the way
constexpr uint32_t kRangeTop = 1u << 24;  // renormalize below this range
constexpr int kRangeMaxRawBits = 16;      // equiprobable bits coded at once

class RangeEncoder {
 public:
  explicit RangeEncoder(std::vector<uint8_t>& out) : out_(out) {}
  void Bit(uint16_t& p, uint32_t bit) {
    const uint32_t bound = (range_ >> kRangeProbBits) * p;
    if (!bit) {
      range_ = bound;
      p = uint16_t(p + (((1u << kRangeProbBits) - p) >> kRangeAdaptShift));
    } else {
      low_ += bound;
      range_ -= bound;
      p = uint16_t(p - (p >> kRangeAdaptShift));
    }
    Normalize();
  }
  // `bits` (1..16) equiprobable bits: value < 2^bits.
  void Raw(uint32_t value, int bits) {
    range_ >>= bits;
    low_ += uint64_t(range_) * value;
    Normalize();
  }
  // Flushes: the output is then complete (the decoder reads exactly these bytes).
  void Finish() {
    for (int i = 0; i < 5; ++i) ShiftLow();
  }

 private:
  void Normalize() {
    while (range_ < kRangeTop) {
      range_ <<= 8;
      ShiftLow();
    }
  }
  void ShiftLow() {
    if (uint32_t(low_) < 0xFF000000u || (low_ >> 32) != 0) {
      const uint8_t carry = uint8_t(low_ >> 32);
      uint8_t byte = cache_;
      do {
        out_.push_back(uint8_t(byte + carry));
        byte = 0xFF;
      } while (--pending_ != 0);
      cache_ = uint8_t(uint32_t(low_) >> 24);
    }
    ++pending_;
    low_ = uint64_t(uint32_t(low_) << 8);
  }
  std::vector<uint8_t>& out_;
  uint64_t low_ = 0;
  uint32_t range_ = 0xFFFFFFFFu;
  uint8_t cache_ = 0;
  uint64_t pending_ = 1;
};

// Reads what RangeEncoder wrote. Never reads outside [data, data + bytes); a stream that is
// truncated, has bytes left over, does not start with its 0 byte or holds a value the encoder
// cannot have written leaves ok() false (the values read are then garbage, but in range).
class RangeDecoder {
 public:
  RangeDecoder(const uint8_t* data, size_t bytes) : p_(data), end_(data + bytes) {
    if (bytes < 5 || data[0] != 0) bad_ = true;
    for (int i = 0; i < 5; ++i) code_ = code_ << 8 | Next();
  }
  uint32_t Bit(uint16_t& p) {
    const uint32_t bound = (range_ >> kRangeProbBits) * p;
    uint32_t bit;
    if (code_ < bound) {
      range_ = bound;
      p = uint16_t(p + (((1u << kRangeProbBits) - p) >> kRangeAdaptShift));
      bit = 0;
    } else {
      code_ -= bound;
      range_ -= bound;
      p = uint16_t(p - (p >> kRangeAdaptShift));
      bit = 1;
    }
    Normalize();
    return bit;
  }
  uint32_t Raw(int bits) {
    range_ >>= bits;
    uint32_t v = code_ / range_;
    if (v >> bits) {  // only a hostile stream: the encoder's code lies below range << bits
      bad_ = true;
      v &= (1u << bits) - 1;
    }
    code_ -= v * range_;
    Normalize();
    return v;
  }
  // Every byte read, none missing, no impossible value.
  bool ok() const { return !bad_ && p_ == end_; }

 private:
  uint32_t Next() {
    if (p_ < end_) return *p_++;
    bad_ = true;
    return 0;
  }
  void Normalize() {
    while (range_ < kRangeTop) {
      range_ <<= 8;
      code_ = code_ << 8 | Next();
    }
  }
  const uint8_t* p_;
  const uint8_t* end_;
  uint32_t code_ = 0, range_ = 0xFFFFFFFFu;
  bool bad_ = false;
};

// The most bytes PositionResidualModel gives for vertexCount vertices: an adaptive bit costs at
// most 7.1 bits (a probability stays within 15/2048 of 0 and 1), a coordinate 7 of them and 30
// equiprobable bits; a deflated positions stream may not claim more.
inline size_t PositionStreamBound(size_t vertexCount) { return vertexCount * 34 + 16; }

// A unit's position residuals (each coordinate modulo 2^W, W = 16 or 32), in the order the
// prediction visits the vertices, each with the kind of its prediction (0: parallelogram, 1: an
// edge's midpoint, 2: a neighbour, 3: the vertex visited before). A coordinate's residual r, read
// as a signed W-bit value, is zigzagged (z = 2r for r >= 0, -2r - 1 else) and coded as its bit
// length n (0..W; six adaptive bits, a binary tree, in the context of the prediction's kind, the
// axis and, for y and z, the previous axis's n), then, for n >= 2, bit n - 2 of z (adaptive, per
// kind and n) and the n - 2 bits below it (equiprobable, 16 at a time, highest first). The stream
// starts with `m` (6 equiprobable bits: the writer's median n of the parallelogram residuals, else
// of all), and each unit's models start from a prior around it (Reset).
class PositionResidualModel {
 public:
  static constexpr int kKinds = 4;
  static constexpr int kLengthContexts = 1 + 2 * 34;  // per kind: x, then y and z after each n
  // The models' starting state for a unit whose typical bit length is m: the length trees of kind
  // k give n the prior weight 2^(24 - |n - m - offset_k|) (offsets 0, 2, 2, 4; 0 above W), each
  // node's probability of a 0 floor(2048 x left's weight / both's), kept within [32, 2016]; the
  // high bits' one half.
  void Reset(uint32_t m, int width) {
    static const int kOffset[kKinds] = {0, 2, 2, 4};
    for (auto& p : high_) p = kRangeProbHalf;
    for (int k = 0; k < kKinds; ++k) {
      uint64_t w[64];
      for (int n = 0; n < 64; ++n) {
        const int d = std::abs(n - int(m) - kOffset[k]);
        w[n] = n > 8 * width ? 0 : uint64_t(1) << (d < 24 ? 24 - d : 0);
      }
      uint16_t tree[64];
      for (int depth = 0; depth < 6; ++depth)
        for (int node = 1 << depth; node < 2 << depth; ++node) {  // leaves [first, first + span)
          const int span = 64 >> depth, first = (node - (1 << depth)) * span;
          uint64_t l = 0, r = 0;
          for (int i = 0; i < span / 2; ++i) l += w[first + i];
          for (int i = span / 2; i < span; ++i) r += w[first + i];
          const uint64_t p = l + r ? (l << kRangeProbBits) / (l + r) : kRangeProbHalf;
          tree[node] = uint16_t(std::min<uint64_t>(2016, std::max<uint64_t>(32, p)));
        }
      for (int c = 0; c < kLengthContexts; ++c)
        std::copy(tree + 1, tree + 64, length_ + (k * kLengthContexts + c) * 64 + 1);
    }
  }
  // The writer's m: the median bit length of the parallelogram residuals' coordinates (of all
  // when there are none; 0 for none at all). `kinds` has one entry a vertex, `r` three.
  static uint32_t TypicalLength(const uint64_t* r, const uint8_t* kinds, size_t vertices, int width,
                                std::vector<uint32_t>& scratch) {
    scratch.clear();
    for (int pass = 0; pass < 2 && scratch.empty(); ++pass)
      for (size_t v = 0; v < vertices; ++v)
        if (pass == 1 || kinds[v] == 0)
          for (int c = 0; c < 3; ++c) scratch.push_back(BitLength(ZigZag(r[3 * v + size_t(c)], width)));
    if (scratch.empty()) return 0;
    std::nth_element(scratch.begin(), scratch.begin() + std::ptrdiff_t(scratch.size() / 2), scratch.end());
    return scratch[scratch.size() / 2];
  }
  static uint64_t ZigZag(uint64_t r, int width) {
    const int shift = 64 - 8 * width;
    const int64_t s = int64_t(r << shift) >> shift;  // r as a signed W-bit value
    return s >= 0 ? uint64_t(s) << 1 : (uint64_t(-(s + 1)) << 1) | 1;
  }
  static uint32_t BitLength(uint64_t z) { return z ? uint32_t(64 - __builtin_clzll(z)) : 0; }
  // Codes the three coordinates of one vertex.
  void Encode(RangeEncoder& rc, int kind, const uint64_t* r, int width) {
    uint32_t previous = 0;
    for (int c = 0; c < 3; ++c) {
      const uint64_t z = ZigZag(r[c], width);
      const uint32_t n = BitLength(z);
      uint16_t* tree = length_ + 64 * Context(kind, c, previous);
      uint32_t node = 1;
      for (int i = 5; i >= 0; --i) {
        const uint32_t bit = (n >> i) & 1;
        rc.Bit(tree[node], bit);
        node = node * 2 + bit;
      }
      if (n >= 2) {
        rc.Bit(high_[kind * 34 + int(n)], uint32_t(z >> (n - 2)) & 1);
        for (int left = int(n) - 2; left > 0;) {
          const int take = left < kRangeMaxRawBits ? left : kRangeMaxRawBits;
          left -= take;
          rc.Raw(uint32_t(z >> left) & ((1u << take) - 1), take);
        }
      }
      previous = n;
    }
  }
  // Decodes one vertex's three residuals (mod 2^W) into r. False on a bit length above W.
  bool Decode(RangeDecoder& rc, int kind, uint64_t* r, int width) {
    uint32_t previous = 0;
    for (int c = 0; c < 3; ++c) {
      uint16_t* tree = length_ + 64 * Context(kind, c, previous);
      uint32_t node = 1;
      for (int i = 0; i < 6; ++i) node = node * 2 + rc.Bit(tree[node]);
      const uint32_t n = node - 64;
      if (n > uint32_t(8 * width)) return false;
      uint64_t z = n ? 1 : 0;
      if (n >= 2) {
        z = z << 1 | rc.Bit(high_[kind * 34 + int(n)]);
        for (int left = int(n) - 2; left > 0;) {
          const int take = left < kRangeMaxRawBits ? left : kRangeMaxRawBits;
          left -= take;
          z = z << take | rc.Raw(take);
        }
      }
      const uint64_t mask = width == 8 ? ~uint64_t(0) : (uint64_t(1) << (8 * width)) - 1;
      r[c] = ((z >> 1) ^ (uint64_t(0) - (z & 1))) & mask;
      previous = n;
    }
    return true;
  }

 private:
  static int Context(int kind, int axis, uint32_t previous) {
    return kind * kLengthContexts + (axis == 0 ? 0 : 1 + (axis - 1) * 34 + int(previous));
  }
  uint16_t length_[kKinds * kLengthContexts * 64] = {};  // node 0 of each tree unused
  uint16_t high_[kKinds * 34] = {};
};

}  // namespace lodfile
}  // namespace conelod
