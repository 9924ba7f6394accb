#include "sen3bot/capture/writer.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <vector>

namespace sen3bot::capture {

namespace {

constexpr std::size_t kGapRecordBytes = kRecordHeaderBytes + kGapPayloadBytes;

std::size_t chunk_count(std::size_t payload_bytes) {
  // An empty payload is still one record.
  return payload_bytes == 0 ? 1 : (payload_bytes + kMaxPayloadBytes - 1) / kMaxPayloadBytes;
}

}  // namespace

CaptureWriter::CaptureWriter(std::size_t buffer_capacity_bytes)
    : capacity_bytes_(buffer_capacity_bytes),
      ring_(std::make_unique<std::uint8_t[]>(buffer_capacity_bytes > 0 ? buffer_capacity_bytes : 1)) {}

CaptureWriter::~CaptureWriter() {
  if (is_open()) (void)close();
}

Status CaptureWriter::open(const std::filesystem::path& path, const CaptureInfo& info) {
  std::lock_guard lock(consumer_mutex_);
  if (fd_ >= 0) return Error(Errc::invalid_argument, "capture writer: already open");
  if (info.channels.size() > kMaxChannels)
    return Error::format(Errc::invalid_argument, "capture writer: %zu channels, at most %zu", info.channels.size(),
                         kMaxChannels);
  std::array<bool, 256> declared{};
  for (const ChannelDecl& c : info.channels) {
    if (c.id == kNoChannel) return Error::format(Errc::invalid_argument, "capture writer: channel id %u is reserved", c.id);
    if (declared[c.id]) return Error::format(Errc::invalid_argument, "capture writer: channel id %u declared twice", c.id);
    if (!valid_channel_name(c.name))
      return Error::format(Errc::invalid_argument, "capture writer: channel %u: invalid name \"%.40s\"", c.id,
                           c.name.c_str());
    declared[c.id] = true;
  }

  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return Error::from_errno(errno == ENOENT ? Errc::not_found : Errc::io, path.native(), errno);
  fd_ = fd;

  std::vector<std::uint8_t> head;
  const auto file_header = encode_file_header(info);
  head.insert(head.end(), file_header.begin(), file_header.end());
  for (const ChannelDecl& c : info.channels) append_channel_decl(head, c);
  if (Status s = write_all(head.data(), head.size()); !s) {
    ::close(fd_);
    fd_ = -1;
    return s;
  }

  declared_ = declared;
  start_monotonic_ns_ = info.start_monotonic_ns;
  head_.store(0, std::memory_order_relaxed);
  tail_.store(0, std::memory_order_relaxed);
  last_t_ns_.store(0, std::memory_order_relaxed);
  records_written_.store(0, std::memory_order_relaxed);
  dropped_records_.store(0, std::memory_order_relaxed);
  dropped_bytes_.store(0, std::memory_order_relaxed);
  rejected_records_.store(0, std::memory_order_relaxed);
  unreported_drop_records_.store(0, std::memory_order_relaxed);
  unreported_drop_bytes_.store(0, std::memory_order_relaxed);
  open_.store(true, std::memory_order_release);
  return {};
}

std::size_t CaptureWriter::buffered_bytes() const noexcept {
  return static_cast<std::size_t>(head_.load(std::memory_order_acquire) - tail_.load(std::memory_order_acquire));
}

bool CaptureWriter::record(hal::Nanos now_ns, std::uint8_t channel, Direction direction,
                           std::span<const std::uint8_t> payload) noexcept {
  return append(now_ns, channel, direction == Direction::rx ? RecordKind::rx : RecordKind::tx, payload);
}

bool CaptureWriter::record_baud_change(hal::Nanos now_ns, std::uint8_t channel, std::uint32_t baud) noexcept {
  std::uint8_t payload[kBaudPayloadBytes];
  le::put_u32(payload, baud);
  return append(now_ns, channel, RecordKind::baud_change, payload);
}

void CaptureWriter::ring_put(std::uint64_t at, const std::uint8_t* data, std::size_t size) noexcept {
  if (size == 0) return;
  const std::size_t pos = static_cast<std::size_t>(at % capacity_bytes_);
  const std::size_t first = size < capacity_bytes_ - pos ? size : capacity_bytes_ - pos;
  std::memcpy(ring_.get() + pos, data, first);
  if (first < size) std::memcpy(ring_.get(), data + first, size - first);
}

bool CaptureWriter::append(hal::Nanos now_ns, std::uint8_t channel, RecordKind kind,
                           std::span<const std::uint8_t> payload) noexcept {
  if (!open_.load(std::memory_order_acquire) || !declared_[channel]) {
    rejected_records_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  // Time never goes backwards in a file and never precedes the start, whatever the caller passes.
  hal::Nanos t_ns = 0;
  if (__builtin_sub_overflow(now_ns, start_monotonic_ns_, &t_ns)) t_ns = now_ns < 0 ? 0 : INT64_MAX;
  if (t_ns < 0) t_ns = 0;
  const hal::Nanos last_t_ns = last_t_ns_.load(std::memory_order_relaxed);
  if (t_ns < last_t_ns) t_ns = last_t_ns;

  const std::uint64_t unreported_records = unreported_drop_records_.load(std::memory_order_relaxed);
  const std::size_t chunks = chunk_count(payload.size());
  const std::size_t need = chunks * kRecordHeaderBytes + payload.size() + (unreported_records > 0 ? kGapRecordBytes : 0);

  std::uint64_t head = head_.load(std::memory_order_relaxed);
  const std::uint64_t tail = tail_.load(std::memory_order_acquire);
  const std::uint64_t free_bytes = capacity_bytes_ - (head - tail);
  if (need > free_bytes) {
    dropped_records_.fetch_add(chunks, std::memory_order_relaxed);
    dropped_bytes_.fetch_add(payload.size(), std::memory_order_relaxed);
    unreported_drop_records_.fetch_add(chunks, std::memory_order_relaxed);
    unreported_drop_bytes_.fetch_add(payload.size(), std::memory_order_relaxed);
    return false;
  }

  if (unreported_records > 0) {
    const auto gap_header = encode_record_header(t_ns, kNoChannel, RecordKind::gap, kGapPayloadBytes);
    std::uint8_t gap_payload[kGapPayloadBytes];
    le::put_u64(&gap_payload[0], unreported_records);
    le::put_u64(&gap_payload[8], unreported_drop_bytes_.load(std::memory_order_relaxed));
    ring_put(head, gap_header.data(), gap_header.size());
    ring_put(head + kRecordHeaderBytes, gap_payload, kGapPayloadBytes);
    head += kGapRecordBytes;
    unreported_drop_records_.store(0, std::memory_order_relaxed);
    unreported_drop_bytes_.store(0, std::memory_order_relaxed);
  }
  std::size_t done = 0;
  for (std::size_t i = 0; i < chunks; ++i) {
    const std::size_t left = payload.size() - done;
    const std::size_t size = left < kMaxPayloadBytes ? left : kMaxPayloadBytes;
    const auto header = encode_record_header(t_ns, channel, kind, static_cast<std::uint32_t>(size));
    ring_put(head, header.data(), header.size());
    ring_put(head + kRecordHeaderBytes, payload.data() + done, size);
    head += kRecordHeaderBytes + size;
    done += size;
  }
  last_t_ns_.store(t_ns, std::memory_order_relaxed);
  records_written_.fetch_add(chunks, std::memory_order_relaxed);
  head_.store(head, std::memory_order_release);  // publishes the bytes to flush()
  return true;
}

Status CaptureWriter::write_all(const std::uint8_t* data, std::size_t size) {
  while (size > 0) {
    const ssize_t n = ::write(fd_, data, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      return Error::from_errno(Errc::io, "capture writer: write", errno);
    }
    data += n;
    size -= static_cast<std::size_t>(n);
  }
  return {};
}

Status CaptureWriter::flush_locked() {
  if (fd_ < 0) return {};
  const std::uint64_t head = head_.load(std::memory_order_acquire);
  std::uint64_t tail = tail_.load(std::memory_order_relaxed);
  while (tail != head) {
    const std::size_t pos = static_cast<std::size_t>(tail % capacity_bytes_);
    const std::uint64_t pending = head - tail;
    const std::size_t contiguous = pending < capacity_bytes_ - pos ? static_cast<std::size_t>(pending) : capacity_bytes_ - pos;
    Status s = write_all(ring_.get() + pos, contiguous);
    if (!s) return s;
    tail += contiguous;
    tail_.store(tail, std::memory_order_release);  // the producer may reuse these bytes now
  }
  return {};
}

Status CaptureWriter::flush() {
  std::lock_guard lock(consumer_mutex_);
  return flush_locked();
}

Status CaptureWriter::close() {
  std::lock_guard lock(consumer_mutex_);
  if (fd_ < 0) return {};
  open_.store(false, std::memory_order_release);
  Status status = flush_locked();

  // The trailer goes straight to the file: the ring may be full, and nothing records now.
  const hal::Nanos t_ns = last_t_ns_.load(std::memory_order_relaxed);
  std::uint8_t trailer[kGapRecordBytes + kRecordHeaderBytes + kEndPayloadBytes];
  std::size_t trailer_bytes = 0;
  const std::uint64_t unreported_records = unreported_drop_records_.load(std::memory_order_relaxed);
  if (unreported_records > 0) {
    const auto gap_header = encode_record_header(t_ns, kNoChannel, RecordKind::gap, kGapPayloadBytes);
    std::memcpy(trailer, gap_header.data(), gap_header.size());
    le::put_u64(&trailer[kRecordHeaderBytes], unreported_records);
    le::put_u64(&trailer[kRecordHeaderBytes + 8], unreported_drop_bytes_.load(std::memory_order_relaxed));
    trailer_bytes = kGapRecordBytes;
    unreported_drop_records_.store(0, std::memory_order_relaxed);
    unreported_drop_bytes_.store(0, std::memory_order_relaxed);
  }
  const auto end_header = encode_record_header(t_ns, kNoChannel, RecordKind::end, kEndPayloadBytes);
  std::memcpy(&trailer[trailer_bytes], end_header.data(), end_header.size());
  le::put_u64(&trailer[trailer_bytes + kRecordHeaderBytes], records_written_.load(std::memory_order_relaxed));
  le::put_u64(&trailer[trailer_bytes + kRecordHeaderBytes + 8], dropped_records_.load(std::memory_order_relaxed));
  trailer_bytes += kRecordHeaderBytes + kEndPayloadBytes;
  if (status) status = write_all(trailer, trailer_bytes);

  if (::close(fd_) != 0 && status) status = Error::from_errno(Errc::io, "capture writer: close", errno);
  fd_ = -1;
  return status;
}

}  // namespace sen3bot::capture
