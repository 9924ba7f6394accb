#!/usr/bin/python3
"""RTSP test peer: Debian's gst-rtsp-server on 127.0.0.1 with H.264 and MJPEG mounts.

Prints "READY <port>" on stdout once listening. Mounts:
  /h264       640x360 15 fps, x264 zerolatency, STAP-A + FU-A, SPS/PPS in band and in sprop
  /h264_fua   1280x720 10 fps at 4 Mbit/s, mtu 1400: every I-frame is many FU-A packets
  /mjpeg      640x360 JPEG type 1 (4:2:0), Q=255 with in-band tables
  /mjpeg720   1280x720 JPEG type 1, 10 fps
  /mjpeg422   640x360 JPEG type 0 (4:2:2)
  /mjpeg_dri  JPEG type 65 (restart markers), when --dri-file names an MKV of such JPEGs
"""
import argparse
import sys

import gi

gi.require_version("Gst", "1.0")
gi.require_version("GstRtspServer", "1.0")
gi.require_version("GstRtsp", "1.0")
from gi.repository import GLib, Gst, GstRtsp, GstRtspServer  # noqa: E402

MOUNTS = {
    "/h264": "videotestsrc is-live=true pattern=ball ! video/x-raw,width=640,height=360,framerate=15/1 "
             "! x264enc tune=zerolatency speed-preset=ultrafast key-int-max=15 "
             "! rtph264pay name=pay0 pt=96 config-interval=-1 aggregate-mode=zero-latency",
    "/h264_fua": "videotestsrc is-live=true pattern=smpte ! video/x-raw,width=1280,height=720,framerate=10/1 "
                 "! x264enc tune=zerolatency speed-preset=ultrafast bitrate=4000 key-int-max=10 "
                 "! rtph264pay name=pay0 pt=96 config-interval=-1 mtu=1400",
    "/mjpeg": "videotestsrc is-live=true pattern=ball ! video/x-raw,format=I420,width=640,height=360,framerate=15/1 "
              "! jpegenc quality=75 ! rtpjpegpay name=pay0 pt=26",
    "/mjpeg720": "videotestsrc is-live=true pattern=smpte ! video/x-raw,format=I420,width=1280,height=720,framerate=10/1 "
                 "! jpegenc quality=75 ! rtpjpegpay name=pay0 pt=26",
    "/mjpeg422": "videotestsrc is-live=true ! video/x-raw,format=Y42B,width=640,height=360,framerate=15/1 "
                 "! jpegenc quality=75 ! rtpjpegpay name=pay0 pt=26",
}


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--port", type=int, default=0)
    parser.add_argument("--auth", choices=["none", "basic", "digest"], default="none")
    parser.add_argument("--user", default="admin")
    parser.add_argument("--password", default="secret")
    parser.add_argument("--session-timeout", type=int, default=0)
    parser.add_argument("--dri-file", default="")
    args = parser.parse_args()

    Gst.init(None)
    server = GstRtspServer.RTSPServer()
    server.set_address("127.0.0.1")
    server.set_service(str(args.port))
    mounts = server.get_mount_points()
    launches = dict(MOUNTS)
    if args.dri_file:
        launches["/mjpeg_dri"] = (f"filesrc location={args.dri_file} ! matroskademux ! jpegparse "
                                  "! rtpjpegpay name=pay0 pt=26")
    for path, launch in launches.items():
        factory = GstRtspServer.RTSPMediaFactory()
        factory.set_launch("( " + launch + " )")
        factory.set_shared(True)
        if args.auth != "none":
            factory.add_role_from_structure(Gst.Structure.from_string(
                "user, media.factory.access=(boolean)true, media.factory.construct=(boolean)true")[0])
        mounts.add_factory(path, factory)

    if args.auth != "none":
        auth = GstRtspServer.RTSPAuth()
        token = GstRtspServer.RTSPToken()
        token.set_string("media.factory.role", "user")
        if args.auth == "basic":
            auth.add_basic(GstRtspServer.RTSPAuth.make_basic(args.user, args.password), token)
            auth.set_supported_methods(GstRtsp.RTSPAuthMethod.BASIC)
        else:
            auth.add_digest(args.user, args.password, token)
            auth.set_supported_methods(GstRtsp.RTSPAuthMethod.DIGEST)
        server.set_auth(auth)

    if args.session_timeout > 0:
        def on_client(_server, client):
            client.connect("new-session", lambda _c, session: session.set_timeout(args.session_timeout))
        server.connect("client-connected", on_client)

    # Without a periodic cleanup sessions never expire.
    pool = server.get_session_pool()
    GLib.timeout_add_seconds(1, lambda: (pool.cleanup(), True)[1])

    if server.attach(None) == 0:
        print("attach failed", file=sys.stderr)
        return 1
    print(f"READY {server.get_bound_port()}", flush=True)
    GLib.MainLoop().run()
    return 0


if __name__ == "__main__":
    sys.exit(main())
