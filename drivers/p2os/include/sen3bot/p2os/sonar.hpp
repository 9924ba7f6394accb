#pragma once
// The Pioneer 3-DX sonar ring: 8 transducers in front, 8 behind (ARIA's p3dx-sh.p), each a
// pose on the body (x forward, y left, mm) and a heading (degrees). ARCOS fires one transducer
// of each bank every SONARCYCLE ms, in disc order, and reports each reading once, in the next
// SIP: with the default 40 ms cycle and 100 ms SIPs, two or three a bank per SIP, every disc
// once per 320 ms.
#include <array>
#include <cstddef>

namespace sen3bot::p2os {

struct SonarMount {
  double x_mm, y_mm, heading_deg;
};

inline constexpr std::size_t kSonarDiscs = 16;
inline constexpr std::size_t kSonarBank = 8;  // discs 0-7 front, 8-15 rear
inline constexpr std::array<SonarMount, kSonarDiscs> kP3dxSonar = {{
    {69, 136, 90}, {114, 119, 50}, {148, 78, 30}, {166, 27, 10},
    {166, -27, -10}, {148, -78, -30}, {114, -119, -50}, {69, -136, -90},
    {-157, -136, -90}, {-203, -119, -130}, {-237, -78, -150}, {-255, -27, -170},
    {-255, 27, 170}, {-237, 78, 150}, {-203, 119, 130}, {-157, 136, 90},
}};
inline constexpr double kSonarBeamDeg = 15.0;  // the cone an echo comes from, full width
inline constexpr double kSonarMinRangeM = 0.1;  // nearer echoes arrive while it still rings
inline constexpr double kSonarMaxRangeM = 5.0;

}  // namespace sen3bot::p2os
