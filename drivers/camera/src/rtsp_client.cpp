#include "sen3bot/camera/rtsp_client.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>

namespace sen3bot::camera {
namespace {

constexpr std::size_t kRxBufferBytes = 256 * 1024;  // > one interleaved frame (64 KiB) + headers
constexpr std::size_t kTxBufferBytes = 16 * 1024;
constexpr std::size_t kUdpDatagramBytes = 65536;
constexpr std::string_view kUserAgent = "sen3bot-camera/1";
constexpr int kRtspStatusUnauthorized = 401;
constexpr int kRtspStatusForbidden = 403;
constexpr int kRtspStatusNotFound = 404;
constexpr int kRtspStatusSessionNotFound = 454;
constexpr int kRtspStatusAggregateNotAllowed = 459;
constexpr int kRtspStatusOnlyAggregate = 460;
constexpr int kRtspStatusUnsupportedTransport = 461;

hal::Nanos ms(int v) { return hal::millis(v); }

// "SETUP: 503 Service Unavailable"
Error status_error(Errc code, const char* what, const RtspMessage& msg) {
  return Error::format(code, "%s: %d %.*s", what, msg.status, static_cast<int>(msg.reason.size()), msg.reason.data());
}

}  // namespace

const char* to_string(RtpTransport t) { return t == RtpTransport::udp ? "udp" : "tcp"; }

const char* to_string(ClientState s) {
  switch (s) {
    case ClientState::idle: return "idle";
    case ClientState::options: return "options";
    case ClientState::describe: return "describe";
    case ClientState::setup: return "setup";
    case ClientState::play: return "play";
    case ClientState::playing: return "playing";
    case ClientState::backoff: return "backoff";
    case ClientState::failed: return "failed";
  }
  return "?";
}

Result<std::unique_ptr<RtspClient>> RtspClient::create(RtspClientConfig config, EncodedFrameSink& sink) {
  auto url = parse_rtsp_url(config.url);
  if (!url) return url.error();
  if (config.max_frame_bytes == 0 || config.max_frame_bytes > 64 * 1024 * 1024) {
    return Error(Errc::config, "max_frame_bytes must be 1 B..64 MiB");
  }
  if (config.reorder_depth_packets < 1 || config.reorder_depth_packets > 256) {
    return Error(Errc::config, "reorder_depth_packets must be 1..256");
  }
  RtspUrl target = *url;
  return std::unique_ptr<RtspClient>(new RtspClient(std::move(config), std::move(target), sink));
}

RtspClient::RtspClient(RtspClientConfig config, RtspUrl target, EncodedFrameSink& sink)
    : config_(std::move(config)),
      target_(std::move(target)),
      sink_(sink),
      request_url_(target_.request_uri()),
      rng_(std::random_device{}()),
      rx_(kRxBufferBytes),
      tx_(kTxBufferBytes),
      udp_buffer_(kUdpDatagramBytes) {
  Credentials creds = config_.credentials.empty() ? Credentials{target_.user, target_.password} : config_.credentials;
  auth_.set_credentials(std::move(creds));
  our_ssrc_ = static_cast<std::uint32_t>(rng_());
  info_.transport = config_.transport;
  reorder_ = std::make_unique<ReorderBuffer>(static_cast<std::size_t>(config_.reorder_depth_packets), 2048);
}

std::size_t RtspClient::poll_fds(int* out, std::size_t capacity) const {
  std::size_t n = 0;
  if (tcp_ && n < capacity) out[n++] = tcp_->poll_fd();
  if (rtp_socket_ && n < capacity) out[n++] = rtp_socket_->poll_fd();
  if (rtcp_socket_ && n < capacity) out[n++] = rtcp_socket_->poll_fd();
  return n;
}

void RtspClient::close_connection() {
  tcp_.reset();
  rtp_socket_.reset();
  rtcp_socket_.reset();
  server_rtcp_known_ = false;
  rx_size_ = 0;
  tx_size_ = 0;
  pending_ = Pending{};
  info_.session_id.clear();
}

void RtspClient::fail(hal::Nanos now, const Error& why) {
  last_error_ = why;
  close_connection();
  ++stats_.reconnects;
  backoff_ms_ = backoff_ms_ == 0 ? config_.backoff_initial_ms : std::min(backoff_ms_ * 2, config_.backoff_max_ms);
  backoff_until_ns_ = now + ms(backoff_ms_);
  state_ = ClientState::backoff;
}

void RtspClient::give_up(const Error& why) {
  last_error_ = why;
  close_connection();
  state_ = ClientState::failed;
}

void RtspClient::start_connection(hal::Nanos now) {
  close_connection();
  // Resolution and connect block for at most connect_timeout_ms; this runs on the camera's
  // own non-real-time thread.
  auto stream = hal::TcpStream::connect(target_.host, target_.port, config_.connect_timeout_ms);
  if (!stream) {
    fail(now, stream.error());
    return;
  }
  tcp_ = std::move(*stream);
  ++stats_.connects;
  auth_.reset();
  tried_fallback_ = false;
  info_ = StreamInfo{};
  info_.transport = config_.transport;
  sequence_.reset();
  reorder_->clear();
  have_last_extended_ = false;
  ssrc_locked_ = false;
  candidate_count_ = 0;
  if (depacketizer_) depacketizer_->reset();
  state_ = ClientState::options;
  send_request(now, "OPTIONS", request_url_, "");
}

bool RtspClient::queue_bytes(std::span<const std::uint8_t> bytes) {
  if (tx_size_ + bytes.size() > tx_.size()) return false;
  std::memcpy(tx_.data() + tx_size_, bytes.data(), bytes.size());
  tx_size_ += bytes.size();
  return flush_output();
}

bool RtspClient::flush_output() {
  if (!tcp_ || tx_size_ == 0) return true;
  auto n = tcp_->write(std::span<const std::uint8_t>(tx_.data(), tx_size_));
  if (!n) return false;
  std::memmove(tx_.data(), tx_.data() + *n, tx_size_ - *n);
  tx_size_ -= *n;
  return true;
}

bool RtspClient::send_request(hal::Nanos now, std::string method, std::string uri, std::string extra) {
  pending_.active = true;
  pending_.method = std::move(method);
  pending_.uri = std::move(uri);
  pending_.extra_headers = std::move(extra);
  pending_.cseq = next_cseq_++;
  pending_.sent_ns = now;
  pending_.auth_retried = false;
  pending_.stale_retried = false;
  std::string text = pending_.method + " " + pending_.uri + " RTSP/1.0\r\nCSeq: " + std::to_string(pending_.cseq) +
                     "\r\nUser-Agent: " + std::string(kUserAgent) + "\r\n";
  if (!info_.session_id.empty()) text += "Session: " + info_.session_id + "\r\n";
  if (auth_.active()) {
    char cnonce[17];
    std::snprintf(cnonce, sizeof cnonce, "%08x%08x", static_cast<unsigned>(rng_()), static_cast<unsigned>(rng_()));
    text += "Authorization: " + auth_.authorization(pending_.method, pending_.uri, cnonce) + "\r\n";
  }
  text += pending_.extra_headers;
  text += "\r\n";
  if (!queue_bytes(std::span(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()))) {
    fail(now, Error(Errc::disconnected, "RTSP request could not be sent"));
    return false;
  }
  return true;
}

void RtspClient::resend_pending(hal::Nanos now, bool stale_retry) {
  Pending p = pending_;
  send_request(now, p.method, p.uri, p.extra_headers);
  pending_.auth_retried = true;
  pending_.stale_retried = p.stale_retried || stale_retry;
}

void RtspClient::step(hal::Nanos now) {
  if (state_ == ClientState::failed) return;
  if (state_ == ClientState::idle) {
    start_connection(now);
    return;
  }
  if (state_ == ClientState::backoff) {
    if (now >= backoff_until_ns_) start_connection(now);
    return;
  }
  if (!flush_output()) {
    fail(now, Error(Errc::disconnected, "RTSP connection closed while sending"));
    return;
  }
  read_tcp(now);
  if (state_ == ClientState::backoff) return;
  read_udp(now);
  if (state_ == ClientState::backoff) return;
  if (pending_.active && now - pending_.sent_ns > ms(config_.response_timeout_ms)) {
    fail(now, Error::format(Errc::timeout, "no reply to %s within %d ms", pending_.method.c_str(), config_.response_timeout_ms));
    return;
  }
  if (state_ == ClientState::playing) playing_timers(now);
}

void RtspClient::playing_timers(hal::Nanos now) {
  if (now - last_media_ns_ > ms(config_.no_media_timeout_ms)) {
    fail(now, Error::format(Errc::timeout, "no RTP for %d ms", config_.no_media_timeout_ms));
    return;
  }
  if (info_.transport == RtpTransport::udp && reorder_->held() > 0 &&
      now - reorder_hold_since_ns_ > ms(config_.reorder_timeout_ms)) {
    drain_reorder(now, true);
  }
  if (config_.keepalive && !pending_.active && now >= next_keepalive_ns_) {
    // Every timeout/2 (RFC 2326 §12.37), GET_PARAMETER when offered, else OPTIONS.
    ++stats_.keepalives_sent;
    next_keepalive_ns_ = now + hal::seconds(info_.session_timeout_s) / 2;
    send_request(now, info_.get_parameter_keepalive ? "GET_PARAMETER" : "OPTIONS",
                 info_.get_parameter_keepalive ? aggregate_url_ : request_url_, "");
    if (state_ != ClientState::playing) return;
  }
  if (config_.keepalive && now >= next_rtcp_ns_) {
    next_rtcp_ns_ = now + ms(config_.rtcp_interval_ms);
    send_receiver_report(now);
  }
}

void RtspClient::read_tcp(hal::Nanos now) {
  for (int round = 0; round < 64 && tcp_; ++round) {
    if (rx_size_ == rx_.size()) {
      fail(now, Error(Errc::protocol, "RTSP receive buffer full without a complete item"));
      return;
    }
    auto n = tcp_->read(std::span<std::uint8_t>(rx_.data() + rx_size_, rx_.size() - rx_size_));
    if (!n) {
      fail(now, n.error());
      return;
    }
    if (*n == 0) break;
    rx_size_ += *n;
    std::size_t pos = 0;
    while (pos < rx_size_ && tcp_) {
      auto item = demux_next(std::span<const std::uint8_t>(rx_.data() + pos, rx_size_ - pos));
      if (!item) {
        fail(now, item.error());
        return;
      }
      if (item->kind == DemuxKind::need_more) break;
      if (item->kind == DemuxKind::interleaved) {
        if (item->channel == rtp_channel_ && state_ >= ClientState::play) on_rtp(now, item->payload);
      } else if (item->kind == DemuxKind::message) {
        on_message(now, item->message);
        if (state_ == ClientState::backoff) return;
      } else {
        stats_.garbage_bytes += item->consumed;
      }
      pos += item->consumed;
    }
    if (!tcp_) return;
    std::memmove(rx_.data(), rx_.data() + pos, rx_size_ - pos);
    rx_size_ -= pos;
  }
}

void RtspClient::read_udp(hal::Nanos now) {
  for (int round = 0; round < 256 && rtp_socket_; ++round) {
    auto got = rtp_socket_->recv_from(udp_buffer_);
    if (!got || !got->has_value()) break;
    const hal::UdpReceived& r = **got;
    if (r.truncated) {
      ++stats_.rtp_invalid;
      continue;
    }
    on_rtp(now, std::span<const std::uint8_t>(udp_buffer_.data(), r.size));
  }
  for (int round = 0; round < 16 && rtcp_socket_; ++round) {
    auto got = rtcp_socket_->recv_from(udp_buffer_);  // sender reports: read and ignore
    if (!got || !got->has_value()) break;
  }
}

void RtspClient::on_message(hal::Nanos now, const RtspMessage& msg) {
  if (!msg.is_response) {
    // §D.1: answer server requests; we implement none of them.
    ++stats_.server_requests;
    const std::string reply = "RTSP/1.0 501 Not Implemented\r\nCSeq: " + std::to_string(msg.cseq().value_or(0)) + "\r\n\r\n";
    queue_bytes(std::span(reinterpret_cast<const std::uint8_t*>(reply.data()), reply.size()));
    return;
  }
  on_response(now, msg);
}

void RtspClient::on_response(hal::Nanos now, const RtspMessage& msg) {
  if (!pending_.active || msg.cseq() != pending_.cseq) return;  // stale or unsolicited: ignore
  pending_.active = false;
  if (msg.status == kRtspStatusUnauthorized) {
    if (!auth_.has_credentials()) {
      give_up(Error::format(Errc::permission, "%s: 401 Unauthorized: the camera requires credentials and none are "
                            "configured", pending_.method.c_str()));
      return;
    }
    mem::StaticVector<std::string_view, 8> challenges;
    for (const RtspHeader& h : msg.headers) {
      if (iequals(h.name, "WWW-Authenticate")) (void)challenges.push_back(h.value);
    }
    auto challenge = choose_challenge(std::span<const std::string_view>(challenges.data(), challenges.size()));
    if (!challenge) {
      give_up(Error::format(challenge.error().code(), "%s: 401 Unauthorized: %s", pending_.method.c_str(),
                            challenge.error().c_str()));
      return;
    }
    // A 401 to a request that carried credentials rejects them, unless it only says the nonce
    // went stale (once per request): the same credentials with the new nonce may pass.
    if (pending_.auth_retried && (!challenge->stale || pending_.stale_retried)) {
      give_up(Error::format(Errc::permission, "%s: 401 Unauthorized: the camera rejected the credentials of user '%s'",
                            pending_.method.c_str(), auth_.user().c_str()));
      return;
    }
    const bool stale_retry = pending_.auth_retried;
    ++stats_.auth_retries;
    auth_.set_challenge(*challenge);
    resend_pending(now, stale_retry);
    return;
  }
  const std::string method = pending_.method;
  if (state_ == ClientState::playing) {
    if (msg.status == kRtspStatusSessionNotFound) {
      fail(now, Error(Errc::disconnected, "454 Session Not Found: the session expired"));
    } else if (msg.status >= 400 && method == "GET_PARAMETER") {
      info_.get_parameter_keepalive = false;  // Thingino answers 454/501: OPTIONS from now on
    }
    return;
  }
  switch (state_) {
    case ClientState::options:
      if (msg.status == 200) {
        if (auto pub = msg.header("Public")) info_.get_parameter_keepalive = method_listed(*pub, "GET_PARAMETER");
      }
      // Some servers fail OPTIONS but play fine; DESCRIBE decides.
      state_ = ClientState::describe;
      send_request(now, "DESCRIBE", request_url_, "Accept: application/sdp\r\n");
      break;
    case ClientState::describe:
      if (msg.status == kRtspStatusNotFound || msg.status == kRtspStatusForbidden) {
        // The path is wrong or not ours to play: the same request will get the same answer.
        const std::string what = "DESCRIBE " + request_url_;
        give_up(status_error(msg.status == kRtspStatusNotFound ? Errc::not_found : Errc::permission, what.c_str(), msg));
        return;
      }
      if (msg.status != 200) {
        fail(now, status_error(Errc::protocol, "DESCRIBE", msg));
        return;
      }
      on_describe(now, msg);
      break;
    case ClientState::setup:
      if (msg.status == kRtspStatusUnsupportedTransport && config_.transport_fallback && !tried_fallback_) {
        tried_fallback_ = true;
        ++stats_.transport_fallbacks;
        info_.transport = info_.transport == RtpTransport::udp ? RtpTransport::tcp_interleaved : RtpTransport::udp;
        send_setup(now);
        return;
      }
      if (msg.status != 200) {
        fail(now, status_error(Errc::protocol, "SETUP", msg));
        return;
      }
      on_setup(now, msg);
      break;
    case ClientState::play:
      if ((msg.status == kRtspStatusOnlyAggregate || msg.status == kRtspStatusAggregateNotAllowed) &&
          info_.play_url != track_url_) {
        send_play(now, track_url_);  // the server wants per-track PLAY
        return;
      }
      if (msg.status != 200) {
        fail(now, status_error(Errc::protocol, "PLAY", msg));
        return;
      }
      state_ = ClientState::playing;
      ever_played_ = true;
      backoff_ms_ = 0;
      play_started_ns_ = now;
      last_media_ns_ = now;
      next_keepalive_ns_ = now + hal::seconds(info_.session_timeout_s) / 2;
      next_rtcp_ns_ = now + ms(config_.rtcp_interval_ms);
      break;
    default:
      break;
  }
}

void RtspClient::on_describe(hal::Nanos now, const RtspMessage& msg) {
  // A DESCRIBE reply may lack Content-Type; the body is SDP when it starts with v=0.
  auto sdp = parse_sdp(msg.body);
  if (!sdp) {
    fail(now, sdp.error());
    return;
  }
  sdp_ = std::move(*sdp);
  const SdpMedia* video = sdp_.first_supported_video();
  if (video == nullptr) {
    give_up(no_supported_video(sdp_));
    return;
  }
  const std::string base = choose_base_url(msg.header("Content-Base").value_or(""),
                                           msg.header("Content-Location").value_or(""), request_url_);
  track_url_ = resolve_control(base, video->control);
  // No session-level control: PLAY the request URL (VStarcam, rtsp-streaming-server).
  aggregate_url_ = sdp_.session_control.empty() ? request_url_ : resolve_control(base, sdp_.session_control);
  info_.codec = video->codec;
  info_.payload_type = video->payload_type;
  info_.sdp_width_px = video->width_px;
  info_.sdp_height_px = video->height_px;
  info_.sdp_framerate_hz = video->framerate_hz;
  info_.setup_url = track_url_;
  if (!depacketizer_ || (video->codec == VideoCodec::h264) != (dynamic_cast<H264Depacketizer*>(depacketizer_.get()) != nullptr)) {
    if (video->codec == VideoCodec::h264) {
      depacketizer_ = std::make_unique<H264Depacketizer>(config_.max_frame_bytes);
    } else {
      depacketizer_ = std::make_unique<JpegDepacketizer>(config_.max_frame_bytes);
    }
  }
  depacketizer_->reset();
  if (auto* h264 = dynamic_cast<H264Depacketizer*>(depacketizer_.get())) h264->set_parameter_sets(video->parameter_sets);
  if (auto* jpeg = dynamic_cast<JpegDepacketizer*>(depacketizer_.get())) {
    jpeg->set_fallback_dimensions(video->width_px, video->height_px);
  }
  state_ = ClientState::setup;
  send_setup(now);
}

void RtspClient::send_setup(hal::Nanos now) {
  std::string transport;
  if (info_.transport == RtpTransport::tcp_interleaved) {
    transport = "Transport: RTP/AVP/TCP;unicast;interleaved=0-1\r\n";
  } else {
    // Bind the pair before SETUP; an even RTP port is conventional, so retry a few times.
    rtp_socket_.reset();
    rtcp_socket_.reset();
    for (int attempt = 0; attempt < 16 && !rtcp_socket_; ++attempt) {
      auto rtp = hal::UdpSocket::bind("", 0);
      if (!rtp) break;
      const std::uint16_t port = (*rtp)->local_port();
      if (port % 2 != 0 || port == 65534) continue;
      auto rtcp = hal::UdpSocket::bind("", static_cast<std::uint16_t>(port + 1));
      if (!rtcp) continue;
      rtp_socket_ = std::move(*rtp);
      rtcp_socket_ = std::move(*rtcp);
    }
    if (!rtcp_socket_) {
      fail(now, Error(Errc::io, "could not bind an RTP/RTCP UDP port pair"));
      return;
    }
    (void)rtp_socket_->set_receive_buffer(static_cast<std::size_t>(config_.udp_receive_buffer_bytes));
    const unsigned port = rtp_socket_->local_port();
    transport = "Transport: RTP/AVP;unicast;client_port=" + std::to_string(port) + "-" + std::to_string(port + 1) + "\r\n";
  }
  send_request(now, "SETUP", track_url_, transport);
}

void RtspClient::on_setup(hal::Nanos now, const RtspMessage& msg) {
  const auto session = msg.header("Session");
  if (!session) {
    fail(now, Error(Errc::protocol, "SETUP reply without Session"));
    return;
  }
  auto parsed = parse_session(*session);
  if (!parsed) {
    fail(now, parsed.error());
    return;
  }
  info_.session_id = std::string(parsed->id);
  info_.session_timeout_s = parsed->timeout_s;
  const auto transport_value = msg.header("Transport");
  if (!transport_value) {
    fail(now, Error(Errc::protocol, "SETUP reply without Transport"));
    return;
  }
  auto transport = parse_transport(*transport_value);
  if (!transport) {
    fail(now, transport.error());
    return;
  }
  if (transport->tcp != (info_.transport == RtpTransport::tcp_interleaved)) {
    fail(now, Error(Errc::protocol, "server chose a transport we did not offer"));
    return;
  }
  if (transport->tcp) {
    rtp_channel_ = transport->rtp_channel;  // the server may pick other channels
    rtcp_channel_ = transport->rtcp_channel;
  } else if (transport->server_rtcp_port > 0) {
    auto endpoint = hal::resolve_udp_endpoint(target_.host, static_cast<std::uint16_t>(transport->server_rtcp_port));
    if (endpoint) {
      server_rtcp_ = *endpoint;
      server_rtcp_known_ = true;
    }
  }
  if (transport->ssrc) {
    ssrc_ = *transport->ssrc;
    ssrc_locked_ = false;  // lock on the first packet: servers' ssrc= values are unreliable
  }
  state_ = ClientState::play;
  send_play(now, aggregate_url_);
}

void RtspClient::send_play(hal::Nanos now, const std::string& url) {
  info_.play_url = url;
  send_request(now, "PLAY", url, "Range: npt=0.000-\r\n");
}

void RtspClient::on_rtp(hal::Nanos now, std::span<const std::uint8_t> datagram) {
  auto packet = parse_rtp(datagram);
  if (!packet || packet->payload_type != info_.payload_type) {
    ++stats_.rtp_invalid;
    return;
  }
  ++stats_.rtp_packets;
  stats_.rtp_bytes += datagram.size();
  last_media_ns_ = now;
  if (!ssrc_locked_) {
    ssrc_locked_ = true;
    ssrc_ = packet->ssrc;
  } else if (packet->ssrc != ssrc_) {
    // A new SSRC for good (encoder restart) after two in a row: start over with it.
    if (packet->ssrc == candidate_ssrc_) {
      ++candidate_count_;
    } else {
      candidate_ssrc_ = packet->ssrc;
      candidate_count_ = 1;
    }
    if (candidate_count_ < static_cast<int>(SequenceTracker::kMinSequential)) {
      ++stats_.rtp_invalid;
      return;
    }
    ssrc_ = packet->ssrc;
    candidate_count_ = 0;
    sequence_.reset();
    reorder_->clear();
    have_last_extended_ = false;
    if (depacketizer_) depacketizer_->reset();
  }
  std::uint64_t extended = 0;
  const auto verdict = sequence_.update(packet->sequence, extended);
  if (verdict == SequenceTracker::Verdict::duplicate_or_late || verdict == SequenceTracker::Verdict::probation) {
    ++stats_.rtp_late_or_duplicate;
    return;
  }
  if (verdict == SequenceTracker::Verdict::restart) {
    reorder_->clear();
    have_last_extended_ = false;
  }
  if (info_.transport == RtpTransport::tcp_interleaved) {
    std::uint32_t lost = 0;
    if (have_last_extended_) {
      if (extended <= last_extended_) {
        ++stats_.rtp_late_or_duplicate;
        return;
      }
      lost = static_cast<std::uint32_t>(std::min<std::uint64_t>(extended - last_extended_ - 1, 0xFFFFFFFFu));
    }
    have_last_extended_ = true;
    last_extended_ = extended;
    deliver(now, *packet, lost);
    return;
  }
  auto pushed = reorder_->push(extended, datagram);
  while (pushed == ReorderBuffer::PushResult::ahead) {
    drain_reorder(now, true);
    pushed = reorder_->push(extended, datagram);
  }
  if (pushed == ReorderBuffer::PushResult::late || pushed == ReorderBuffer::PushResult::duplicate) {
    ++stats_.rtp_late_or_duplicate;
  } else if (pushed == ReorderBuffer::PushResult::too_big) {
    ++stats_.rtp_invalid;
  } else if (reorder_->held() == 1) {
    reorder_hold_since_ns_ = now;
  }
  drain_reorder(now, false);
}

void RtspClient::drain_reorder(hal::Nanos now, bool flush) {
  ReorderBuffer::Released r;
  bool first = true;
  while (reorder_->pop(r, flush && first)) {
    first = false;
    auto packet = parse_rtp(r.packet);
    if (packet) deliver(now, *packet, r.lost_before);
  }
  if (reorder_->held() > 0) reorder_hold_since_ns_ = now;
}

void RtspClient::deliver(hal::Nanos now, const RtpPacket& packet, std::uint32_t lost_before) {
  stats_.rtp_lost += lost_before;
  if (depacketizer_) depacketizer_->push(packet, lost_before > 0, now, sink_);
}

void RtspClient::send_receiver_report(hal::Nanos now) {
  (void)now;
  std::uint8_t packet[4 + 64];
  ReceiverReportInputs in;
  in.our_ssrc = our_ssrc_;
  in.have_source = ssrc_locked_;
  in.source_ssrc = ssrc_;
  in.cumulative_lost = static_cast<std::uint32_t>(std::min<std::uint64_t>(sequence_.lost(), 0xFFFFFFu));
  in.extended_highest_seq = static_cast<std::uint32_t>(sequence_.max_extended());
  const std::size_t n = build_receiver_report(in, std::span<std::uint8_t>(packet + 4, sizeof packet - 4));
  if (n == 0) return;
  if (info_.transport == RtpTransport::tcp_interleaved) {
    packet[0] = kInterleavedMagic;
    packet[1] = static_cast<std::uint8_t>(rtcp_channel_);
    packet[2] = static_cast<std::uint8_t>(n >> 8);
    packet[3] = static_cast<std::uint8_t>(n);
    if (queue_bytes(std::span<const std::uint8_t>(packet, n + 4))) ++stats_.receiver_reports_sent;
  } else if (rtcp_socket_ && server_rtcp_known_) {
    if (rtcp_socket_->send_to(std::span<const std::uint8_t>(packet + 4, n), server_rtcp_)) ++stats_.receiver_reports_sent;
  }
}

void RtspClient::stop(hal::Nanos now) {
  if (tcp_ && !info_.session_id.empty()) {
    send_request(now, "TEARDOWN", aggregate_url_, "");
    (void)flush_output();
  }
  close_connection();
  state_ = ClientState::idle;
}

}  // namespace sen3bot::camera
