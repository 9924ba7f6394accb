#include "sen3bot/image/image_file.hpp"

#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>

// jpeglib.h needs FILE and size_t declared first.
#include <jpeglib.h>
#include <png.h>
#include <zlib.h>

namespace sen3bot::image {
namespace {

struct JpegError {
  jpeg_error_mgr manager;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

void jpeg_error_exit(j_common_ptr info) {
  auto* error = reinterpret_cast<JpegError*>(info->err);
  (*info->err->format_message)(info, error->message);
  std::longjmp(error->jump, 1);
}

void jpeg_quiet(j_common_ptr, int) {}

// The whole image is in memory: running out of bytes suspends the decoder, which then yields
// no more rows, as with OpenCV's source (libjpeg's own memory source would invent an end).
void source_nothing(j_decompress_ptr) {}
boolean source_exhausted(j_decompress_ptr) { return FALSE; }
void source_skip(j_decompress_ptr info, long bytes) {
  jpeg_source_mgr* source = info->src;
  const std::size_t n = bytes > 0 ? static_cast<std::size_t>(bytes) : 0;
  const std::size_t skipped = n < source->bytes_in_buffer ? n : source->bytes_in_buffer;
  source->next_input_byte += skipped;
  source->bytes_in_buffer -= skipped;
}

// EXIF orientation (tag 0x0112 of the first IFD) from an APP1 marker; 1 (as stored) when absent.
int exif_orientation(const jpeg_decompress_struct& info) {
  for (jpeg_saved_marker_ptr m = info.marker_list; m != nullptr; m = m->next) {
    if (m->marker != JPEG_APP0 + 1 || m->data_length < 14 || std::memcmp(m->data, "Exif\0\0", 6) != 0) continue;
    const std::uint8_t* tiff = m->data + 6;
    const std::size_t size = m->data_length - 6;
    const bool little = tiff[0] == 'I' && tiff[1] == 'I';
    if (!little && !(tiff[0] == 'M' && tiff[1] == 'M')) return 1;
    auto u16 = [&](std::size_t at) -> std::uint32_t {
      return little ? tiff[at] | (tiff[at + 1] << 8) : (tiff[at] << 8) | tiff[at + 1];
    };
    auto u32 = [&](std::size_t at) -> std::uint32_t { return little ? u16(at) | (u16(at + 2) << 16) : (u16(at) << 16) | u16(at + 2); };
    const std::size_t ifd = u32(4);
    if (ifd + 2 > size) return 1;
    const std::size_t entries = u16(ifd);
    for (std::size_t e = 0; e < entries && ifd + 2 + 12 * (e + 1) <= size; ++e) {
      const std::size_t at = ifd + 2 + 12 * e;
      if (u16(at) == 0x0112 && u16(at + 2) == 3) {
        const std::uint32_t value = u16(at + 8);
        return value >= 1 && value <= 8 ? static_cast<int>(value) : 1;
      }
    }
    return 1;
  }
  return 1;
}

// Turns the decoded picture upright as its EXIF orientation says (as imread/imdecode do).
void apply_orientation(int orientation, Image& image) {
  if (orientation <= 1) return;
  const bool transpose = orientation >= 5;
  const bool flip_x = orientation == 2 || orientation == 3 || orientation == 6 || orientation == 7;
  const bool flip_y = orientation == 3 || orientation == 4 || orientation == 7 || orientation == 8;
  const std::size_t w = transpose ? image.height_px : image.width_px;
  const std::size_t h = transpose ? image.width_px : image.height_px;
  const std::size_t c = image.channels;
  std::vector<std::uint8_t> turned(image.pixels.size());
  for (std::size_t y = 0; y < h; ++y) {
    for (std::size_t x = 0; x < w; ++x) {
      const std::size_t x1 = flip_x ? w - 1 - x : x;
      const std::size_t y1 = flip_y ? h - 1 - y : y;
      const std::size_t sx = transpose ? y1 : x1;
      const std::size_t sy = transpose ? x1 : y1;
      std::memcpy(&turned[(y * w + x) * c], &image.pixels[(sy * image.width_px + sx) * c], c);
    }
  }
  image.pixels.swap(turned);
  image.width_px = static_cast<std::uint32_t>(w);
  image.height_px = static_cast<std::uint32_t>(h);
}

// Plain C state only between setjmp and longjmp: nothing with a destructor is skipped.
bool decode_jpeg_into(const std::uint8_t* data, std::size_t size, int channels, Image& out, int& orientation,
                      char* message) {
  jpeg_decompress_struct info{};
  JpegError error{};
  jpeg_source_mgr source{};
  volatile bool rows_read = false;
  info.err = jpeg_std_error(&error.manager);
  error.manager.error_exit = jpeg_error_exit;
  error.manager.emit_message = jpeg_quiet;
  if (setjmp(error.jump) != 0) {
    // As imdecode: an image whose rows were all read is kept even when finishing fails
    // (a truncated stream).
    std::memcpy(message, error.message, JMSG_LENGTH_MAX);
    jpeg_destroy_decompress(&info);
    return rows_read;
  }
  jpeg_create_decompress(&info);
  source.init_source = source_nothing;
  source.fill_input_buffer = source_exhausted;
  source.skip_input_data = source_skip;
  source.resync_to_restart = jpeg_resync_to_restart;
  source.term_source = source_nothing;
  source.next_input_byte = data;
  source.bytes_in_buffer = size;
  info.src = &source;
  jpeg_save_markers(&info, JPEG_APP0 + 1, 0xFFFF);
  if (jpeg_read_header(&info, TRUE) != JPEG_HEADER_OK) {
    std::snprintf(message, JMSG_LENGTH_MAX, "truncated JPEG header");
    jpeg_destroy_decompress(&info);
    return false;
  }
  if (static_cast<std::uint64_t>(info.image_width) * info.image_height > kMaxPixels) {
    std::snprintf(message, JMSG_LENGTH_MAX, "%u x %u pixels: more than %llu", info.image_width, info.image_height,
                  static_cast<unsigned long long>(kMaxPixels));
    jpeg_destroy_decompress(&info);
    return false;
  }
  // OpenCV reads CMYK through a conversion of its own; camera frames are YCbCr or grey.
  if (info.num_components == 4) {
    std::snprintf(message, JMSG_LENGTH_MAX, "CMYK JPEG not supported");
    jpeg_destroy_decompress(&info);
    return false;
  }
  info.out_color_space = channels == 1 ? JCS_GRAYSCALE : JCS_EXT_BGR;
  orientation = exif_orientation(info);
  if (!jpeg_start_decompress(&info)) {
    std::snprintf(message, JMSG_LENGTH_MAX, "truncated JPEG data");
    jpeg_destroy_decompress(&info);
    return false;
  }
  const std::size_t row_bytes = static_cast<std::size_t>(info.output_width) * static_cast<std::size_t>(channels);
  out.width_px = info.output_width;
  out.height_px = info.output_height;
  out.channels = static_cast<std::uint8_t>(channels);
  out.pixels.resize(row_bytes * info.output_height);
  // Rows after the data ran out repeat the last one decoded, as imdecode leaves them.
  for (std::size_t y = 0; y < info.output_height; ++y) {
    JSAMPROW row = out.pixels.data() + row_bytes * y;
    if (jpeg_read_scanlines(&info, &row, 1) == 1) continue;
    if (y == 0) {
      std::memset(row, 0, row_bytes);
    } else {
      std::memcpy(row, row - row_bytes, row_bytes);
    }
  }
  rows_read = true;
  jpeg_finish_decompress(&info);
  jpeg_destroy_decompress(&info);
  return true;
}

struct PngRead {
  std::span<const std::uint8_t> bytes;
  std::size_t at = 0;
};

void png_read_bytes(png_structp png, png_bytep data, png_size_t length) {
  auto* source = static_cast<PngRead*>(png_get_io_ptr(png));
  if (source->bytes.size() - source->at < length) png_error(png, "truncated PNG data");
  std::memcpy(data, source->bytes.data() + source->at, length);
  source->at += length;
}

void png_error_exit(png_structp png, png_const_charp text) {
  auto* message = static_cast<char*>(png_get_error_ptr(png));
  std::snprintf(message, 200, "%s", text);
  png_longjmp(png, 1);
}

void png_warning_quiet(png_structp, png_const_charp) {}

bool decode_png_into(std::span<const std::uint8_t> bytes, int channels, Image& out, char* message) {
  PngRead source{bytes, 0};
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, message, png_error_exit, png_warning_quiet);
  if (png == nullptr) return false;
  png_infop info = png_create_info_struct(png);
  if (info == nullptr || setjmp(png_jmpbuf(png)) != 0) {
    png_destroy_read_struct(&png, &info, nullptr);
    return false;
  }
  png_set_read_fn(png, &source, png_read_bytes);
  png_read_info(png, info);
  png_set_expand(png);     // palette and low-bit grey to 8 bits, tRNS to alpha
  png_set_strip_16(png);
  png_set_strip_alpha(png);
  const png_byte colour = png_get_color_type(png, info);
  const bool grey_source = (colour & PNG_COLOR_MASK_COLOR) == 0;
  if (channels == 1 && !grey_source) png_set_rgb_to_gray_fixed(png, 1, -1, -1);
  if (channels == 3 && grey_source) png_set_gray_to_rgb(png);
  if (channels == 3) png_set_bgr(png);
  png_read_update_info(png, info);
  out.width_px = png_get_image_width(png, info);
  out.height_px = png_get_image_height(png, info);
  if (static_cast<std::uint64_t>(out.width_px) * out.height_px > kMaxPixels) {
    std::snprintf(message, 200, "%u x %u pixels: more than %llu", out.width_px, out.height_px,
                  static_cast<unsigned long long>(kMaxPixels));
    png_destroy_read_struct(&png, &info, nullptr);
    out.width_px = out.height_px = 0;
    return false;
  }
  out.channels = static_cast<std::uint8_t>(channels);
  const std::size_t row_bytes = png_get_rowbytes(png, info);
  if (row_bytes != static_cast<std::size_t>(out.width_px) * static_cast<std::size_t>(channels)) {
    std::snprintf(message, 200, "unexpected PNG row size");
    png_destroy_read_struct(&png, &info, nullptr);
    return false;
  }
  out.pixels.resize(row_bytes * out.height_px);
  const int passes = png_set_interlace_handling(png);
  for (int pass = 0; pass < passes; ++pass) {
    for (std::uint32_t y = 0; y < out.height_px; ++y) png_read_row(png, out.pixels.data() + row_bytes * y, nullptr);
  }
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  return true;
}

bool encode_png(std::FILE* file, const std::uint8_t* pixels, std::uint32_t width, std::uint32_t height,
                std::size_t stride, int channels, char* message) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, message, png_error_exit, png_warning_quiet);
  if (png == nullptr) return false;
  png_infop info = png_create_info_struct(png);
  if (info == nullptr || setjmp(png_jmpbuf(png)) != 0) {
    png_destroy_write_struct(&png, &info);
    return false;
  }
  png_init_io(png, file);
  // imwrite's defaults for PNG: speed over size.
  png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_SUB);
  png_set_compression_level(png, Z_BEST_SPEED);
  png_set_compression_strategy(png, Z_RLE);
  const int type = channels == 1 ? PNG_COLOR_TYPE_GRAY : channels == 3 ? PNG_COLOR_TYPE_RGB : PNG_COLOR_TYPE_RGBA;
  png_set_IHDR(png, info, width, height, 8, type, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  if (channels > 1) png_set_bgr(png);
  for (std::uint32_t y = 0; y < height; ++y) png_write_row(png, pixels + stride * y);
  png_write_end(png, info);
  png_destroy_write_struct(&png, &info);
  return true;
}

}  // namespace

Status decode_jpeg(std::span<const std::uint8_t> jpeg, int channels, Image& out) {
  if (channels != 1 && channels != 3) return Error(Errc::invalid_argument, "decode_jpeg: channels must be 1 or 3");
  if (jpeg.size() < 4 || jpeg[0] != 0xFF || jpeg[1] != 0xD8) return Error(Errc::protocol, "not a JPEG (no SOI marker)");
  char message[JMSG_LENGTH_MAX] = {};
  int orientation = 1;
  if (!decode_jpeg_into(jpeg.data(), jpeg.size(), channels, out, orientation, message)) {
    out.width_px = out.height_px = 0;
    return Error::format(Errc::protocol, "JPEG: %s", message);
  }
  apply_orientation(orientation, out);
  return Status::success();
}

Status read_image(const std::string& path, int channels, Image& out) {
  if (channels != 1 && channels != 3) return Error(Errc::invalid_argument, "read_image: channels must be 1 or 3");
  std::ifstream file(path, std::ios::binary);
  if (!file) return Error::format(Errc::not_found, "%s: cannot open", path.c_str());
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  static constexpr std::uint8_t kPngSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (bytes.size() >= 8 && std::memcmp(bytes.data(), kPngSignature, 8) == 0) {
    char message[200] = {};
    if (!decode_png_into(bytes, channels, out, message)) return Error::format(Errc::protocol, "%s: PNG: %s", path.c_str(), message);
    return Status::success();
  }
  if (bytes.size() >= 2 && bytes[0] == 0xFF && bytes[1] == 0xD8) {
    if (Status s = decode_jpeg(bytes, channels, out); !s) return Error::format(s.error().code(), "%s: %s", path.c_str(), s.error().c_str());
    return Status::success();
  }
  return Error::format(Errc::protocol, "%s: neither a JPEG nor a PNG image", path.c_str());
}

Status write_png(const std::string& path, const std::uint8_t* pixels, std::uint32_t width_px, std::uint32_t height_px,
                 std::size_t stride_bytes, int channels) {
  if (channels != 1 && channels != 3 && channels != 4) return Error(Errc::invalid_argument, "write_png: channels must be 1, 3 or 4");
  if (width_px == 0 || height_px == 0) return Error(Errc::invalid_argument, "write_png: empty image");
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) return Error::format(Errc::io, "%s: cannot create", path.c_str());
  char message[200] = {};
  const bool written = encode_png(file, pixels, width_px, height_px, stride_bytes, channels, message);
  const bool closed = std::fclose(file) == 0;
  if (!written) return Error::format(Errc::io, "%s: PNG: %s", path.c_str(), message);
  if (!closed) return Error::format(Errc::io, "%s: write failed", path.c_str());
  return Status::success();
}

}  // namespace sen3bot::image
