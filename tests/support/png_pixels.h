#pragma once
// A small PNG reader for the figure tests: 8-bit RGB or RGBA, not interlaced (what gnuplot's
// pngcairo terminal writes), decompressed with zlib, the scanline filters undone. Enough to ask
// what a person would see: which colours a region of the figure holds.

#include <zlib.h>

#include <array>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

namespace dpc::testing {

struct PngPixels {
  uint32_t width_px = 0;
  uint32_t height_px = 0;
  std::vector<std::array<uint8_t, 3>> rgb;  ///< row-major; alpha dropped

  const std::array<uint8_t, 3>& at(uint32_t x, uint32_t y) const { return rgb[size_t{y} * width_px + x]; }

  /// Pixels in rows [y0, y1) whose colour is within `tolerance` (per channel) of `colour`.
  size_t CountNear(uint32_t y0, uint32_t y1, const std::array<uint8_t, 3>& colour, int tolerance = 40) const {
    size_t count = 0;
    for (uint32_t y = y0; y < y1 && y < height_px; ++y) {
      for (uint32_t x = 0; x < width_px; ++x) {
        const auto& p = at(x, y);
        if (std::abs(p[0] - colour[0]) <= tolerance && std::abs(p[1] - colour[1]) <= tolerance &&
            std::abs(p[2] - colour[2]) <= tolerance) {
          ++count;
        }
      }
    }
    return count;
  }
};

inline std::array<uint8_t, 3> HexColour(const std::string& hex) {  // "#RRGGBB"
  const auto byte = [&](size_t at) { return static_cast<uint8_t>(std::stoi(hex.substr(at, 2), nullptr, 16)); };
  return {byte(1), byte(3), byte(5)};
}

inline PngPixels ReadPngPixels(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const std::vector<uint8_t> file((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (file.size() < 8 || file[1] != 'P' || file[2] != 'N' || file[3] != 'G') {
    throw std::runtime_error(path + " is not a PNG");
  }
  const auto be32 = [&](size_t at) {
    return (uint32_t{file[at]} << 24) | (uint32_t{file[at + 1]} << 16) | (uint32_t{file[at + 2]} << 8) |
           uint32_t{file[at + 3]};
  };
  PngPixels png;
  int channels = 0;
  std::vector<uint8_t> compressed;
  for (size_t at = 8; at + 8 <= file.size();) {
    const uint32_t length = be32(at);
    const std::string type(file.begin() + static_cast<long>(at) + 4, file.begin() + static_cast<long>(at) + 8);
    if (at + 12 + length > file.size()) throw std::runtime_error(path + ": truncated chunk " + type);
    const uint8_t* data = file.data() + at + 8;
    if (type == "IHDR") {
      png.width_px = be32(at + 8);
      png.height_px = be32(at + 12);
      if (data[8] != 8 || data[12] != 0 || (data[9] != 2 && data[9] != 6)) {
        throw std::runtime_error(path + ": only 8-bit RGB/RGBA, not interlaced");
      }
      channels = data[9] == 6 ? 4 : 3;
    } else if (type == "IDAT") {
      compressed.insert(compressed.end(), data, data + length);
    }
    at += 12 + length;
  }
  const size_t stride = size_t{png.width_px} * static_cast<size_t>(channels);
  std::vector<uint8_t> raw((stride + 1) * png.height_px);
  uLongf raw_size = raw.size();
  if (channels == 0 || uncompress(raw.data(), &raw_size, compressed.data(), compressed.size()) != Z_OK ||
      raw_size != raw.size()) {
    throw std::runtime_error(path + ": cannot decompress the image data");
  }
  std::vector<uint8_t> previous(stride, 0), line(stride);
  png.rgb.reserve(size_t{png.width_px} * png.height_px);
  for (uint32_t y = 0; y < png.height_px; ++y) {
    const uint8_t filter = raw[y * (stride + 1)];
    const uint8_t* src = &raw[y * (stride + 1) + 1];
    for (size_t i = 0; i < stride; ++i) {
      const int a = i >= static_cast<size_t>(channels) ? line[i - static_cast<size_t>(channels)] : 0;
      const int b = previous[i];
      const int c = i >= static_cast<size_t>(channels) ? previous[i - static_cast<size_t>(channels)] : 0;
      int predicted = 0;
      switch (filter) {
        case 0: predicted = 0; break;
        case 1: predicted = a; break;
        case 2: predicted = b; break;
        case 3: predicted = (a + b) / 2; break;
        case 4: {
          const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
          predicted = pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
          break;
        }
        default: throw std::runtime_error(path + ": bad scanline filter");
      }
      line[i] = static_cast<uint8_t>(src[i] + predicted);
    }
    for (uint32_t x = 0; x < png.width_px; ++x) {
      const uint8_t* p = &line[size_t{x} * static_cast<size_t>(channels)];
      png.rgb.push_back({p[0], p[1], p[2]});
    }
    previous.swap(line);
  }
  return png;
}

}  // namespace dpc::testing
