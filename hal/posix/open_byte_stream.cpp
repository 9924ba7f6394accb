#include "sen3bot/hal/serial.hpp"
#include "sen3bot/hal/tcp.hpp"

namespace sen3bot::hal {

Result<std::unique_ptr<ByteStream>> open_byte_stream(std::string_view spec, std::uint32_t baud,
                                                     int connect_timeout_ms) {
  if (is_tcp_url(spec)) {
    Result<TcpEndpoint> endpoint = parse_tcp_url(spec);
    if (!endpoint) return endpoint.error();
    Result<std::unique_ptr<TcpStream>> stream = TcpStream::connect(endpoint->host, endpoint->port, connect_timeout_ms);
    if (!stream) return stream.error();
    return std::unique_ptr<ByteStream>(std::move(stream).value());
  }
  Result<std::unique_ptr<SerialPort>> port = SerialPort::open(spec, baud);
  if (!port) return port.error();
  return std::unique_ptr<ByteStream>(std::move(port).value());
}

}  // namespace sen3bot::hal
