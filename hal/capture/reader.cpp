#include "sen3bot/capture/reader.hpp"

#include <cerrno>
#include <cinttypes>
#include <cstdio>
#include <memory>

namespace sen3bot::capture {

// Every validation error names the byte offset first, so a hex editor finds it at once.
#define SEN3BOT_CAPTURE_FAIL(offset, fmt, ...)                                                   \
  Error::format(Errc::protocol, "capture offset %" PRIu64 ": " fmt, static_cast<std::uint64_t>(offset) \
                    __VA_OPT__(, ) __VA_ARGS__)

Result<CaptureReader> CaptureReader::open(std::span<const std::uint8_t> bytes) {
  CaptureReader reader(bytes);
  reader.channel_index_.fill(-1);
  const std::uint8_t* p = bytes.data();
  const std::size_t size = bytes.size();

  for (std::size_t i = 0; i < kMagic.size() && i < size; ++i) {
    if (p[i] != kMagic[i]) return SEN3BOT_CAPTURE_FAIL(i, "bad magic (not a sen3bot capture file)");
  }
  if (size < kFileHeaderBytes)
    return SEN3BOT_CAPTURE_FAIL(size, "truncated file header (%zu bytes, the header is %zu)", size, kFileHeaderBytes);
  const std::uint16_t version = le::get_u16(p + 8);
  if (version != kFormatVersion)
    return SEN3BOT_CAPTURE_FAIL(8, "unknown format version %u (this reader knows %u)", version, kFormatVersion);
  const std::uint16_t channel_count = le::get_u16(p + 10);
  if (channel_count > kMaxChannels)
    return SEN3BOT_CAPTURE_FAIL(10, "%u channels declared, at most %zu", channel_count, kMaxChannels);
  const std::uint32_t flags = le::get_u32(p + 12);
  if (flags != 0) return SEN3BOT_CAPTURE_FAIL(12, "unknown flags 0x%08" PRIx32, flags);
  reader.info_.start_wall_ns = le::get_i64(p + 16);
  reader.info_.start_monotonic_ns = le::get_i64(p + 24);

  std::size_t at = kFileHeaderBytes;
  reader.info_.channels.reserve(channel_count);
  for (std::uint16_t c = 0; c < channel_count; ++c) {
    if (size - at < kChannelDeclBytes)
      return SEN3BOT_CAPTURE_FAIL(at, "truncated channel declaration %u of %u", c + 1u, static_cast<unsigned>(channel_count));
    const std::uint8_t id = p[at];
    const std::uint8_t name_bytes = p[at + 1];
    if (id == kNoChannel) return SEN3BOT_CAPTURE_FAIL(at, "channel id %u is reserved", id);
    if (reader.channel_index_[id] >= 0) return SEN3BOT_CAPTURE_FAIL(at, "channel id %u declared twice", id);
    if (name_bytes == 0 || name_bytes > kMaxChannelNameBytes)
      return SEN3BOT_CAPTURE_FAIL(at + 1, "channel name length %u outside 1..%zu", name_bytes, kMaxChannelNameBytes);
    if (le::get_u16(p + at + 2) != 0) return SEN3BOT_CAPTURE_FAIL(at + 2, "reserved channel field is not zero");
    const std::uint32_t baud = le::get_u32(p + at + 4);
    if (size - at - kChannelDeclBytes < name_bytes)
      return SEN3BOT_CAPTURE_FAIL(at + kChannelDeclBytes, "truncated channel name (%u bytes declared)", name_bytes);
    const char* name = reinterpret_cast<const char*>(p + at + kChannelDeclBytes);
    for (std::size_t i = 0; i < name_bytes; ++i) {
      if (name[i] < 0x21 || name[i] > 0x7E)
        return SEN3BOT_CAPTURE_FAIL(at + kChannelDeclBytes + i, "channel name byte 0x%02x is not printable ASCII",
                                    static_cast<unsigned>(p[at + kChannelDeclBytes + i]));
    }
    reader.channel_index_[id] = static_cast<std::int16_t>(reader.info_.channels.size());
    reader.info_.channels.push_back(ChannelDecl{id, std::string(name, name_bytes), baud});
    at += kChannelDeclBytes + name_bytes;
  }
  reader.offset_ = at;
  return reader;
}

const ChannelDecl* CaptureReader::channel(std::uint8_t id) const noexcept {
  const std::int16_t index = channel_index_[id];
  return index < 0 ? nullptr : &info_.channels[static_cast<std::size_t>(index)];
}

Error CaptureReader::fail(Error error) {
  error_ = error;
  return error;
}

Result<std::optional<Record>> CaptureReader::next() {
  if (error_) return *error_;
  const std::size_t size = bytes_.size();
  const std::uint64_t at = offset_;
  if (at == size) return std::optional<Record>{};
  if (saw_end_) return fail(SEN3BOT_CAPTURE_FAIL(at, "%" PRIu64 " bytes after the end record", size - at));
  if (size - at < kRecordHeaderBytes)
    return fail(SEN3BOT_CAPTURE_FAIL(at, "truncated record header (%" PRIu64 " of %zu bytes)", size - at, kRecordHeaderBytes));

  const std::uint8_t* h = bytes_.data() + at;
  Record r;
  r.file_offset = at;
  r.t_ns = le::get_i64(h);
  r.channel = h[8];
  const std::uint8_t kind = h[9];
  const std::uint32_t payload_bytes = le::get_u32(h + 12);

  if (r.t_ns < 0) return fail(SEN3BOT_CAPTURE_FAIL(at, "negative record time %" PRId64 " ns", r.t_ns));
  if (r.t_ns < last_t_ns_)
    return fail(SEN3BOT_CAPTURE_FAIL(at, "record time %" PRId64 " ns is before the previous record's %" PRId64 " ns",
                                     r.t_ns, last_t_ns_));
  if (kind > kMaxRecordKind) return fail(SEN3BOT_CAPTURE_FAIL(at + 9, "unknown record kind %u", kind));
  r.kind = static_cast<RecordKind>(kind);
  if (le::get_u16(h + 10) != 0) return fail(SEN3BOT_CAPTURE_FAIL(at + 10, "reserved record field is not zero"));
  if (payload_bytes > kMaxPayloadBytes)
    return fail(SEN3BOT_CAPTURE_FAIL(at + 12, "payload length %" PRIu32 " exceeds %zu", payload_bytes, kMaxPayloadBytes));

  const bool data_kind = r.kind == RecordKind::rx || r.kind == RecordKind::tx || r.kind == RecordKind::baud_change;
  if (data_kind && channel_index_[r.channel] < 0)
    return fail(SEN3BOT_CAPTURE_FAIL(at + 8, "unknown channel id %u", r.channel));
  if (!data_kind && r.channel != kNoChannel)
    return fail(SEN3BOT_CAPTURE_FAIL(at + 8, "%.*s record with channel id %u (must be %u)",
                                     static_cast<int>(to_string(r.kind).size()), to_string(r.kind).data(), r.channel,
                                     kNoChannel));
  if (size - at - kRecordHeaderBytes < payload_bytes)
    return fail(SEN3BOT_CAPTURE_FAIL(at, "truncated record (payload of %" PRIu32 " bytes, %" PRIu64 " left)", payload_bytes,
                                     size - at - kRecordHeaderBytes));
  r.payload = bytes_.subspan(static_cast<std::size_t>(at) + kRecordHeaderBytes, payload_bytes);
  const std::uint8_t* payload = r.payload.data();
  const std::uint64_t payload_at = at + kRecordHeaderBytes;

  switch (r.kind) {
    case RecordKind::rx:
    case RecordKind::tx:
      ++data_records_;
      break;
    case RecordKind::baud_change:
      if (payload_bytes != kBaudPayloadBytes)
        return fail(SEN3BOT_CAPTURE_FAIL(at + 12, "baud record payload is %" PRIu32 " bytes, expected %zu", payload_bytes,
                                         kBaudPayloadBytes));
      r.baud = le::get_u32(payload);
      if (r.baud == 0) return fail(SEN3BOT_CAPTURE_FAIL(payload_at, "baud change to 0"));
      ++data_records_;
      break;
    case RecordKind::gap:
      if (payload_bytes != kGapPayloadBytes)
        return fail(SEN3BOT_CAPTURE_FAIL(at + 12, "gap record payload is %" PRIu32 " bytes, expected %zu", payload_bytes,
                                         kGapPayloadBytes));
      r.dropped_records = le::get_u64(payload);
      r.dropped_bytes = le::get_u64(payload + 8);
      if (r.dropped_records == 0) return fail(SEN3BOT_CAPTURE_FAIL(payload_at, "gap record with no dropped records"));
      if (r.dropped_records > UINT64_MAX - gap_dropped_records_)
        return fail(SEN3BOT_CAPTURE_FAIL(payload_at, "dropped record count overflows"));
      gap_dropped_records_ += r.dropped_records;
      break;
    case RecordKind::end:
      if (payload_bytes != kEndPayloadBytes)
        return fail(SEN3BOT_CAPTURE_FAIL(at + 12, "end record payload is %" PRIu32 " bytes, expected %zu", payload_bytes,
                                         kEndPayloadBytes));
      r.written_records = le::get_u64(payload);
      r.dropped_records = le::get_u64(payload + 8);
      if (r.written_records != data_records_)
        return fail(SEN3BOT_CAPTURE_FAIL(payload_at, "end record counts %" PRIu64 " records, the file holds %" PRIu64,
                                         r.written_records, data_records_));
      if (r.dropped_records != gap_dropped_records_)
        return fail(SEN3BOT_CAPTURE_FAIL(payload_at + 8, "end record counts %" PRIu64 " dropped records, gaps hold %" PRIu64,
                                         r.dropped_records, gap_dropped_records_));
      saw_end_ = true;
      break;
  }
  last_t_ns_ = r.t_ns;
  offset_ = at + kRecordHeaderBytes + payload_bytes;
  return std::optional<Record>{r};
}

Result<CaptureFile> CaptureFile::parse(std::vector<std::uint8_t> bytes) {
  CaptureFile file;
  file.bytes_ = std::move(bytes);
  auto reader = CaptureReader::open(file.bytes_);
  if (!reader) return reader.error();
  for (;;) {
    auto next = reader->next();
    if (!next) return next.error();
    if (!next->has_value()) break;
    file.records_.push_back(**next);
  }
  file.info_ = reader->info();
  file.complete_ = reader->saw_end_record();
  return file;
}

Result<CaptureFile> CaptureFile::load(const std::filesystem::path& path) {
  struct Closer {
    void operator()(std::FILE* f) const { std::fclose(f); }
  };
  std::unique_ptr<std::FILE, Closer> f(std::fopen(path.c_str(), "rb"));
  if (!f) return Error::from_errno(errno == ENOENT ? Errc::not_found : Errc::io, path.native(), errno);
  std::vector<std::uint8_t> bytes;
  std::uint8_t block[64 * 1024];
  for (;;) {
    const std::size_t n = std::fread(block, 1, sizeof block, f.get());
    if (n > kMaxFileBytes - bytes.size())
      return Error::format(Errc::capacity, "%s: capture larger than %zu bytes", path.c_str(), kMaxFileBytes);
    bytes.insert(bytes.end(), block, block + n);
    if (n < sizeof block) break;
  }
  if (std::ferror(f.get())) return Error::from_errno(Errc::io, path.native(), errno);
  auto file = parse(std::move(bytes));
  if (!file) {
    // Keep the problem, add the file name in front.
    return Error::format(file.error().code(), "%s: %s", path.filename().c_str(), file.error().c_str());
  }
  return file;
}

const ChannelDecl* CaptureFile::channel(std::uint8_t id) const noexcept {
  for (const ChannelDecl& c : info_.channels)
    if (c.id == id) return &c;
  return nullptr;
}

const ChannelDecl* CaptureFile::find_channel(std::string_view name) const noexcept {
  for (const ChannelDecl& c : info_.channels)
    if (c.name == name) return &c;
  return nullptr;
}

std::vector<std::uint8_t> CaptureFile::stream_bytes(std::uint8_t channel, Direction direction) const {
  const RecordKind kind = direction == Direction::rx ? RecordKind::rx : RecordKind::tx;
  std::vector<std::uint8_t> out;
  for (const Record& r : records_)
    if (r.channel == channel && r.kind == kind) out.insert(out.end(), r.payload.begin(), r.payload.end());
  return out;
}

}  // namespace sen3bot::capture

#undef SEN3BOT_CAPTURE_FAIL
