#pragma once
// RTSP 1.0 playback client as a non-blocking state machine: step(now) does whatever I/O is
// ready and advances OPTIONS -> DESCRIBE -> SETUP -> PLAY -> playing, with the 401 retry,
// 461 transport fallback, keep-alive every timeout/2, RTCP receiver reports, and reconnect
// with exponential backoff; a failure that retrying cannot cure (see step()) ends in state
// failed instead. It only ever connects to the configured URL's host: control URLs from the
// camera are used as request URIs on the open connection, never dialled.
#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "sen3bot/camera/auth.hpp"
#include "sen3bot/camera/depacketizer.hpp"
#include "sen3bot/camera/rtp.hpp"
#include "sen3bot/camera/rtsp_message.hpp"
#include "sen3bot/camera/rtsp_url.hpp"
#include "sen3bot/camera/sdp.hpp"
#include "sen3bot/hal/tcp.hpp"
#include "sen3bot/hal/udp.hpp"

namespace sen3bot::camera {

enum class RtpTransport : std::uint8_t { tcp_interleaved, udp };
const char* to_string(RtpTransport t);

struct RtspClientConfig {
  std::string url;                     // rtsp://[user:pass@]host[:port]/path
  Credentials credentials;             // used when set, else the URL's userinfo
  RtpTransport transport = RtpTransport::tcp_interleaved;  // TCP: Wi-Fi loses UDP bursts
  bool transport_fallback = true;      // on 461 try the other transport once
  int connect_timeout_ms = 3000;
  int response_timeout_ms = 5000;      // per request; then reconnect
  int no_media_timeout_ms = 5000;      // playing but no RTP this long: reconnect
  int backoff_initial_ms = 250;        // doubled after each failed attempt
  int backoff_max_ms = 8000;
  int udp_receive_buffer_bytes = 4 * 1024 * 1024;  // default 208 KiB lost I-frame bursts
  int reorder_depth_packets = 8;       // UDP only; TCP arrives in order
  int reorder_timeout_ms = 40;         // release past a hole after this long
  int rtcp_interval_ms = 5000;         // receiver reports (also a keep-alive, ONVIF §5.2.2.2)
  std::size_t max_frame_bytes = 2 * 1024 * 1024;  // one encoded frame; larger ones are dropped
  bool keepalive = true;               // off only to test session expiry
};

// backoff: waiting to reconnect after a failure that may pass (network, timeout, 5xx).
// failed: given up for good (see RtspClient::step); last_error() says why.
enum class ClientState : std::uint8_t { idle, options, describe, setup, play, playing, backoff, failed };
const char* to_string(ClientState s);

struct RtspClientStats {
  std::uint64_t connects = 0;
  std::uint64_t reconnects = 0;
  std::uint64_t rtp_packets = 0;
  std::uint64_t rtp_bytes = 0;
  std::uint64_t rtp_lost = 0;          // sequence holes (also over TCP: servers drop on backlog)
  std::uint64_t rtp_late_or_duplicate = 0;
  std::uint64_t rtp_invalid = 0;       // bad header, other PT, other SSRC
  std::uint64_t keepalives_sent = 0;
  std::uint64_t receiver_reports_sent = 0;
  std::uint64_t server_requests = 0;   // answered with 501
  std::uint64_t garbage_bytes = 0;     // skipped while resynchronising the TCP stream
  std::uint64_t auth_retries = 0;
  std::uint64_t transport_fallbacks = 0;
};

// What DESCRIBE/SETUP settled; valid from state playing on.
struct StreamInfo {
  VideoCodec codec = VideoCodec::unknown;
  int payload_type = -1;
  int sdp_width_px = 0;
  int sdp_height_px = 0;
  double sdp_framerate_hz = 0;
  RtpTransport transport = RtpTransport::tcp_interleaved;
  std::string setup_url;
  std::string play_url;
  std::string session_id;
  int session_timeout_s = 60;
  bool get_parameter_keepalive = false;
};

class RtspClient {
 public:
  static Result<std::unique_ptr<RtspClient>> create(RtspClientConfig config, EncodedFrameSink& sink);

  // Non-blocking; call often (after a poll on poll_fds() or on a timer of a few ms).
  // Reconnects with backoff after network loss, timeouts, 5xx and other statuses, but stops
  // for good (state failed, nothing more sent) when retrying cannot succeed: no video track,
  // only codecs we cannot decode, authentication required without credentials or rejected
  // with them (401 to a request that carried them), 403, or 404 to DESCRIBE (no such stream).
  void step(hal::Nanos now_ns);
  // Sends TEARDOWN (best effort) and closes.
  void stop(hal::Nanos now_ns);

  // Descriptors worth polling for readability right now (TCP, RTP and RTCP sockets).
  [[nodiscard]] std::size_t poll_fds(int* out, std::size_t capacity) const;

  [[nodiscard]] ClientState state() const { return state_; }
  [[nodiscard]] const RtspClientStats& stats() const { return stats_; }
  [[nodiscard]] const StreamInfo& stream() const { return info_; }
  [[nodiscard]] const Depacketizer* depacketizer() const { return depacketizer_.get(); }
  [[nodiscard]] bool failed() const { return state_ == ClientState::failed; }
  // The last reason a connection attempt failed or was dropped ("" when none).
  [[nodiscard]] std::string_view last_error() const { return last_error_.message(); }
  [[nodiscard]] const RtspUrl& target() const { return target_; }

 private:
  RtspClient(RtspClientConfig config, RtspUrl target, EncodedFrameSink& sink);

  struct Pending {
    bool active = false;
    std::string method;
    std::string uri;
    std::string extra_headers;
    std::uint32_t cseq = 0;
    hal::Nanos sent_ns = 0;
    bool auth_retried = false;   // sent again with credentials after a 401
    bool stale_retried = false;  // and once more after a 401 with stale=true
  };

  void start_connection(hal::Nanos now);
  void fail(hal::Nanos now, const Error& why);
  void give_up(const Error& why);  // permanent: no reconnect
  void close_connection();
  bool send_request(hal::Nanos now, std::string method, std::string uri, std::string extra);
  void resend_pending(hal::Nanos now, bool stale_retry);
  bool queue_bytes(std::span<const std::uint8_t> bytes);
  bool flush_output();
  void read_tcp(hal::Nanos now);
  void read_udp(hal::Nanos now);
  void on_message(hal::Nanos now, const RtspMessage& msg);
  void on_response(hal::Nanos now, const RtspMessage& msg);
  void on_describe(hal::Nanos now, const RtspMessage& msg);
  void on_setup(hal::Nanos now, const RtspMessage& msg);
  void send_setup(hal::Nanos now);
  void send_play(hal::Nanos now, const std::string& url);
  void on_rtp(hal::Nanos now, std::span<const std::uint8_t> datagram);
  void deliver(hal::Nanos now, const RtpPacket& packet, std::uint32_t lost_before);
  void drain_reorder(hal::Nanos now, bool flush);
  void send_receiver_report(hal::Nanos now);
  void playing_timers(hal::Nanos now);

  RtspClientConfig config_;
  RtspUrl target_;
  EncodedFrameSink& sink_;
  std::string request_url_;  // the configured URL without userinfo
  ClientState state_ = ClientState::idle;
  RtspClientStats stats_;
  StreamInfo info_;
  Error last_error_;
  Authenticator auth_;
  std::mt19937 rng_;

  std::unique_ptr<hal::TcpStream> tcp_;
  std::unique_ptr<hal::UdpSocket> rtp_socket_;
  std::unique_ptr<hal::UdpSocket> rtcp_socket_;
  hal::UdpEndpoint server_rtcp_{};
  bool server_rtcp_known_ = false;
  std::vector<std::uint8_t> rx_;     // fixed capacity, compacted after each pass
  std::size_t rx_size_ = 0;
  std::vector<std::uint8_t> tx_;     // pending output
  std::size_t tx_size_ = 0;
  std::vector<std::uint8_t> udp_buffer_;
  Pending pending_;
  std::uint32_t next_cseq_ = 1;
  int rtp_channel_ = 0;
  int rtcp_channel_ = 1;
  bool tried_fallback_ = false;
  SessionDescription sdp_;
  std::string aggregate_url_;
  std::string track_url_;
  std::unique_ptr<Depacketizer> depacketizer_;
  SequenceTracker sequence_;
  std::unique_ptr<ReorderBuffer> reorder_;
  hal::Nanos reorder_hold_since_ns_ = 0;
  bool have_last_extended_ = false;
  std::uint64_t last_extended_ = 0;
  bool ssrc_locked_ = false;
  std::uint32_t ssrc_ = 0;
  std::uint32_t candidate_ssrc_ = 0;
  int candidate_count_ = 0;
  std::uint32_t our_ssrc_ = 0;
  hal::Nanos backoff_until_ns_ = 0;
  int backoff_ms_ = 0;
  hal::Nanos last_media_ns_ = 0;
  hal::Nanos next_keepalive_ns_ = 0;
  hal::Nanos next_rtcp_ns_ = 0;
  hal::Nanos play_started_ns_ = 0;
  bool ever_played_ = false;
};

}  // namespace sen3bot::camera
