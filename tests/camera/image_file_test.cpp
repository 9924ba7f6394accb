// JPEG decoding and PNG writing with libjpeg-turbo and libpng directly, checked against the
// OpenCV image codecs they replace: the same pixels (bit for bit) from the camera's decoder,
// `sen3bot detect --image` and the figures, and the same PNG bytes as imwrite.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <initializer_list>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <jpeglib.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "sen3bot/camera/decoder.hpp"
#include "sen3bot/camera/frame_pool.hpp"
#include "sen3bot/image/image_file.hpp"

namespace sen3bot::image {
using namespace sen3bot::camera;
namespace {

const std::string kData = "/usr/share/doc/opencv-doc/examples/data/";

std::vector<std::uint8_t> file_bytes(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
}

cv::Mat as_mat(const Image& image) {
  return {static_cast<int>(image.height_px), static_cast<int>(image.width_px), image.channels == 1 ? CV_8UC1 : CV_8UC3,
          const_cast<std::uint8_t*>(image.pixels.data())};
}

// A BGR image as JPEG with the chroma sampling given (OpenCV 4.6's imencode has no setting).
// orientation > 0 adds an EXIF block with that orientation, big-endian when motorola.
std::vector<std::uint8_t> encode(const cv::Mat& bgr, int h_samp, int v_samp, bool progressive, int orientation = 0,
                                 bool motorola = false) {
  jpeg_compress_struct info{};
  jpeg_error_mgr error{};
  info.err = jpeg_std_error(&error);
  jpeg_create_compress(&info);
  unsigned char* buffer = nullptr;
  unsigned long size = 0;
  jpeg_mem_dest(&info, &buffer, &size);
  info.image_width = static_cast<JDIMENSION>(bgr.cols);
  info.image_height = static_cast<JDIMENSION>(bgr.rows);
  info.input_components = 3;
  info.in_color_space = JCS_EXT_BGR;
  jpeg_set_defaults(&info);
  jpeg_set_quality(&info, 85, TRUE);
  info.comp_info[0].h_samp_factor = h_samp;
  info.comp_info[0].v_samp_factor = v_samp;
  if (progressive) jpeg_simple_progression(&info);
  jpeg_start_compress(&info, TRUE);
  if (orientation > 0) {
    const auto o = static_cast<std::uint8_t>(orientation);
    const std::vector<std::uint8_t> exif =
        motorola ? std::vector<std::uint8_t>{'E', 'x', 'i', 'f', 0, 0, 'M', 'M', 0, 42, 0, 0, 0, 8, 0, 1,
                                             0x01, 0x12, 0, 3, 0, 0, 0, 1, 0, o, 0, 0, 0, 0, 0, 0}
                 : std::vector<std::uint8_t>{'E', 'x', 'i', 'f', 0, 0, 'I', 'I', 42, 0, 8, 0, 0, 0, 1, 0,
                                             0x12, 0x01, 3, 0, 1, 0, 0, 0, o, 0, 0, 0, 0, 0, 0, 0};
    jpeg_write_marker(&info, JPEG_APP0 + 1, exif.data(), static_cast<unsigned>(exif.size()));
  }
  while (info.next_scanline < info.image_height) {
    JSAMPROW row = const_cast<JSAMPROW>(bgr.ptr<std::uint8_t>(static_cast<int>(info.next_scanline)));
    jpeg_write_scanlines(&info, &row, 1);
  }
  jpeg_finish_compress(&info);
  jpeg_destroy_compress(&info);
  std::vector<std::uint8_t> out(buffer, buffer + size);
  std::free(buffer);
  return out;
}

// Photographs and re-encodings of one in the layouts a camera may send: 4:2:0, 4:2:2, 4:4:4,
// progressive, grey, low quality at an odd size.
std::vector<std::pair<std::string, std::vector<std::uint8_t>>> jpegs() {
  std::vector<std::pair<std::string, std::vector<std::uint8_t>>> out;
  for (const char* name : {"building.jpg", "fruits.jpg", "baboon.jpg", "home.jpg", "board.jpg"}) {
    const std::string path = kData + name;
    std::vector<std::uint8_t> bytes = file_bytes(path);
    EXPECT_FALSE(bytes.empty()) << path << " is missing: toolchain/bootstrap.sh installs opencv-doc";
    out.emplace_back(name, std::move(bytes));
  }
  const cv::Mat photo = cv::imread(kData + "fruits.jpg", cv::IMREAD_COLOR);
  if (photo.empty()) return out;
  const cv::Mat odd = photo(cv::Rect(3, 5, 317, 211)).clone();
  const cv::Mat grey = cv::imread(kData + "box.png", cv::IMREAD_GRAYSCALE);
  out.emplace_back("4:2:2", encode(photo, 2, 1, false));
  out.emplace_back("4:4:4", encode(photo, 1, 1, false));
  out.emplace_back("4:2:0 odd size", encode(odd, 2, 2, false));
  out.emplace_back("progressive", encode(photo, 2, 2, true));
  struct Variant {
    const char* name;
    const cv::Mat* image;
    std::vector<int> params;
  };
  const Variant variants[] = {
      {"imencode progressive", &photo, {cv::IMWRITE_JPEG_PROGRESSIVE, 1}},
      {"imencode quality 30, odd size", &odd, {cv::IMWRITE_JPEG_QUALITY, 30}},
      {"imencode grey", &grey, {}},
  };
  for (const Variant& v : variants) {
    std::vector<std::uint8_t> bytes;
    EXPECT_TRUE(cv::imencode(".jpg", *v.image, bytes, v.params)) << v.name;
    out.emplace_back(v.name, std::move(bytes));
  }
  return out;
}

TEST(ImageFile, JpegDecodesToTheSamePixelsAsOpenCvImdecode) {
  const auto cases = jpegs();
  ASSERT_GE(cases.size(), 12u);
  Image image;
  for (const auto& [name, bytes] : cases) {
    for (const int channels : {3, 1}) {
      SCOPED_TRACE(name + (channels == 1 ? " grey" : " colour"));
      ASSERT_TRUE(decode_jpeg(bytes, channels, image));
      const cv::Mat expected = cv::imdecode(bytes, channels == 1 ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR);
      ASSERT_FALSE(expected.empty());
      ASSERT_EQ(image.width_px, static_cast<std::uint32_t>(expected.cols));
      ASSERT_EQ(image.height_px, static_cast<std::uint32_t>(expected.rows));
      ASSERT_EQ(image.channels, channels);
      const cv::Mat decoded = as_mat(image);
      EXPECT_EQ(cv::norm(decoded, expected, cv::NORM_INF), 0.0);
      EXPECT_EQ(cv::mean(decoded), cv::mean(expected));
    }
  }
}

TEST(ImageFile, TheExifOrientationIsAppliedAsImdecodeDoes) {
  const cv::Mat photo = cv::imread(kData + "fruits.jpg", cv::IMREAD_COLOR);
  ASSERT_FALSE(photo.empty());
  const cv::Mat corner = photo(cv::Rect(0, 0, 120, 70)).clone();
  Image image;
  for (const bool motorola : {false, true}) {
    for (int orientation = 1; orientation <= 8; ++orientation) {
      SCOPED_TRACE(std::to_string(orientation) + (motorola ? " MM" : " II"));
      const std::vector<std::uint8_t> bytes = encode(corner, 2, 2, false, orientation, motorola);
      for (const int channels : {3, 1}) {
        const cv::Mat expected = cv::imdecode(bytes, channels == 1 ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR);
        ASSERT_TRUE(decode_jpeg(bytes, channels, image));
        ASSERT_EQ(image.width_px, static_cast<std::uint32_t>(expected.cols));
        ASSERT_EQ(image.height_px, static_cast<std::uint32_t>(expected.rows));
        EXPECT_EQ(cv::norm(as_mat(image), expected, cv::NORM_INF), 0.0);
      }
    }
  }
}

TEST(ImageFile, TheCameraDecoderPublishesWhatImdecodeAndResizeGave) {
  const std::vector<std::uint8_t> bytes = file_bytes(kData + "building.jpg");
  ASSERT_FALSE(bytes.empty());
  const cv::Mat source = cv::imdecode(bytes, cv::IMREAD_COLOR);
  for (const int downscale : {1, 2}) {
    SCOPED_TRACE(downscale);
    auto pool = FramePool::create(3, 1280, 720, PixelFormat::bgr8);
    ASSERT_TRUE(pool);
    auto decoder = FrameDecoder::create(VideoCodec::jpeg, DecoderOptions{downscale, 2 * 1024 * 1024});
    ASSERT_TRUE(decoder);
    EncodedFrame frame;
    frame.codec = VideoCodec::jpeg;
    frame.data = bytes;
    ASSERT_TRUE((*decoder)->decode(frame, **pool, 1));
    FrameHandle handle = (*pool)->acquire_latest();
    ASSERT_TRUE(handle);
    const FrameRef& ref = handle.ref();
    std::uint32_t w = 0;
    std::uint32_t h = 0;
    fit_output_size(static_cast<std::uint32_t>(source.cols), static_cast<std::uint32_t>(source.rows), downscale, 1280,
                    720, w, h);
    ASSERT_EQ(ref.width_px, w);
    ASSERT_EQ(ref.height_px, h);
    cv::Mat expected;
    if (w == static_cast<std::uint32_t>(source.cols) && h == static_cast<std::uint32_t>(source.rows)) {
      expected = source;
    } else {
      cv::resize(source, expected, cv::Size(static_cast<int>(w), static_cast<int>(h)), 0, 0, cv::INTER_AREA);
    }
    const cv::Mat published(static_cast<int>(h), static_cast<int>(w), CV_8UC3, const_cast<std::uint8_t*>(ref.data),
                            ref.stride_bytes);
    EXPECT_EQ(cv::norm(published, expected, cv::NORM_INF), 0.0);
  }
}

TEST(ImageFile, BrokenJpegsAreErrorsAndTruncatedOnesDecodeAsImdecodeDoes) {
  Image image;
  const std::vector<std::uint8_t> noise = {0xFF, 0xD8, 0xFF, 0xC0, 0x00, 0x03, 0x01, 0x02, 0x03};
  EXPECT_FALSE(decode_jpeg(noise, 3, image));
  EXPECT_FALSE(decode_jpeg(std::vector<std::uint8_t>{1, 2, 3, 4, 5}, 3, image));
  EXPECT_FALSE(decode_jpeg(std::vector<std::uint8_t>{}, 1, image));
  // Cut in the header, in the scan and just before the end: an error where imdecode gives
  // nothing, the same pixels where it gives an image.
  int images = 0;
  for (const auto& [name, whole] : jpegs()) {
    for (const std::size_t size : {std::size_t{100}, whole.size() / 4, whole.size() / 2, whole.size() - 2}) {
      SCOPED_TRACE(name + " cut at " + std::to_string(size));
      const std::vector<std::uint8_t> cut(whole.begin(), whole.begin() + static_cast<std::ptrdiff_t>(size));
      for (const int channels : {3, 1}) {
        const cv::Mat expected = cv::imdecode(cut, channels == 1 ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR);
        ASSERT_EQ(decode_jpeg(cut, channels, image).ok(), !expected.empty());
        if (expected.empty()) continue;
        ++images;
        EXPECT_EQ(cv::norm(as_mat(image), expected, cv::NORM_INF), 0.0);
      }
    }
  }
  EXPECT_GT(images, 20);
}

TEST(ImageFile, AHeaderClaimingAHugeImageIsRefusedBeforeItsMemoryIsTaken) {
  std::vector<std::uint8_t> bytes;
  ASSERT_TRUE(cv::imencode(".jpg", cv::Mat(8, 8, CV_8UC3, cv::Scalar(10, 20, 30)), bytes));
  Image image;
  ASSERT_TRUE(decode_jpeg(bytes, 3, image));
  // The baseline frame header (FF C0, length, precision, height, width): 65000 x 65000.
  std::size_t sof = 0;
  while (sof + 9 < bytes.size() && !(bytes[sof] == 0xFF && bytes[sof + 1] == 0xC0)) ++sof;
  ASSERT_LT(sof + 9, bytes.size());
  for (const std::size_t at : {sof + 5, sof + 7}) {
    bytes[at] = 0xFD;
    bytes[at + 1] = 0xE8;
  }
  const Status refused = decode_jpeg(bytes, 3, image);
  ASSERT_FALSE(refused);
  EXPECT_NE(std::string(refused.error().c_str()).find("65000 x 65000"), std::string::npos) << refused.error().c_str();
  EXPECT_EQ(image.width_px, 0u);
}

TEST(ImageFile, PngIsWrittenAsImwriteWritesItAndReadsBack) {
  const cv::Mat colour = cv::imread(kData + "fruits.jpg", cv::IMREAD_COLOR);
  ASSERT_FALSE(colour.empty());
  cv::Mat grey;
  cv::cvtColor(colour, grey, cv::COLOR_BGR2GRAY);
  const std::string dir = ::testing::TempDir();
  for (const cv::Mat* image : std::initializer_list<const cv::Mat*>{&colour, &grey}) {
    const int channels = image->channels();
    SCOPED_TRACE(channels);
    const std::string ours = dir + "/ours.png";
    const std::string theirs = dir + "/theirs.png";
    ASSERT_TRUE(write_png(ours, image->data, static_cast<std::uint32_t>(image->cols),
                          static_cast<std::uint32_t>(image->rows), image->step, channels));
    ASSERT_TRUE(cv::imwrite(theirs, *image));
    EXPECT_EQ(file_bytes(ours), file_bytes(theirs));
    EXPECT_EQ(cv::norm(cv::imread(ours, cv::IMREAD_UNCHANGED), *image, cv::NORM_INF), 0.0);
    Image back;
    ASSERT_TRUE(read_image(ours, 3, back));
    cv::Mat expected = cv::imread(ours, cv::IMREAD_COLOR);
    EXPECT_EQ(cv::norm(as_mat(back), expected, cv::NORM_INF), 0.0);
    std::remove(ours.c_str());
    std::remove(theirs.c_str());
  }
}

TEST(ImageFile, ReadImageTakesJpegAndPngAsImreadDoes) {
  Image image;
  for (const char* name : {"basketball1.png", "building.jpg", "box.png"}) {
    SCOPED_TRACE(name);
    ASSERT_TRUE(read_image(kData + name, 3, image));
    const cv::Mat expected = cv::imread(kData + name, cv::IMREAD_COLOR);
    EXPECT_EQ(cv::norm(as_mat(image), expected, cv::NORM_INF), 0.0);
  }
  const Status missing = read_image("/nonexistent/x.png", 3, image);
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().code(), Errc::not_found);
  EXPECT_FALSE(write_png("/nonexistent/x.png", image.pixels.data(), image.width_px, image.height_px,
                         image.width_px * 3u, 3));
}

}  // namespace
}  // namespace sen3bot::image
