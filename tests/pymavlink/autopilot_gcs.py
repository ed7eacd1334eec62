#!/usr/bin/env python3
"""pymavlink (Ardupilot's Python MAVLink) plays an ArduSub autopilot and QGroundControl against
the VPF firmware's MAVLink line (tests/mavlink.rs runs it).

It makes a pty, prints its slave's path on the first line of stdout ("PTY /dev/pts/N"), and
waits for the firmware to speak there. Then, in real time at 10 Hz, for RUN_S seconds:
- as the autopilot (system 1, component 1): HEARTBEAT (ArduSub in GUIDED) each second,
  GPS_GLOBAL_ORIGIN, and ATTITUDE and LOCAL_POSITION_NED of a simulated vehicle that follows
  the velocity and yaw of the firmware's SET_POSITION_TARGET_LOCAL_NED (as GUIDED does, zeroing
  a velocity target that is 3 s old);
- as the ground station (system 255, component 190), after 1 s: uploads a two-waypoint mission
  to the firmware's component (1:191) with the mission protocol: one item in MAV_FRAME_LOCAL_NED,
  one in MAV_FRAME_GLOBAL_RELATIVE_ALT_INT (converted by the firmware with the origin).

Prints one JSON line at the end with what it saw; exits 0. The Rust test judges it.
"""
import json
import math
import os
import select
import sys
import time
import tty

os.environ["MAVLINK20"] = "1"
from pymavlink.dialects.v20 import ardupilotmega as mavlink2  # noqa: E402

RUN_S = float(os.environ.get("RUN_S", "14"))
ORIGIN = (45.0, 14.0)  # degrees
# Waypoint 1 local NED (north, east) m; waypoint 2 global, 20 m north and 10 m east of it.
WP1 = (8.0, 0.0)
WP2 = (20.0, 10.0)


class Port:
    """The pty master as pymavlink's file."""

    def __init__(self, fd):
        self.fd = fd

    def write(self, b):
        os.write(self.fd, b)


def global_of(north, east):
    lat0, lon0 = ORIGIN
    r = 6378137.0
    lat = lat0 + math.degrees(north / r)
    lon = lon0 + math.degrees(east / (r * math.cos(math.radians(lat0))))
    return int(round(lat * 1e7)), int(round(lon * 1e7))


def main():
    master, slave = os.openpty()
    tty.setraw(master)
    tty.setraw(slave)
    print("PTY", os.ttyname(slave), flush=True)
    port = Port(master)
    ap = mavlink2.MAVLink(port, srcSystem=1, srcComponent=1)
    gcs = mavlink2.MAVLink(port, srcSystem=255, srcComponent=190)
    rx = mavlink2.MAVLink(None)
    rx.robust_parsing = True

    # Simulated vehicle, NED.
    n = e = 0.0
    yaw = 0.0
    vn = ve = 0.0
    target = None  # (vn, ve, yaw, t)
    seen = {
        "setpoints": 0,
        "setpoints_moving": 0,
        "type_masks": [],
        "frames": [],
        "statustext": [],
        "heartbeats": 0,
        "obstacle_distance": None,
        "mission_requests": [],
        "mission_ack": None,
        "first_moving_setpoint": None,
        "bad": 0,
    }
    upload = {"state": "idle"}
    t0 = time.time()
    next_tick = t0
    k = 0
    start = None
    while time.time() - t0 < RUN_S:
        now = time.time()
        if now >= next_tick:
            dt = 0.1
            next_tick += dt
            t = now - t0
            if target is not None and now - target[3] > 3.0:
                target = (0.0, 0.0, target[2], target[3])  # GUIDED's 3 s velocity timeout
            if target is not None:
                vn, ve, yaw = target[0], target[1], target[2]
            n += vn * dt
            e += ve * dt
            tb = int(t * 1000)
            if k % 10 == 0:
                ap.heartbeat_send(
                    mavlink2.MAV_TYPE_SUBMARINE,
                    mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA,
                    mavlink2.MAV_MODE_FLAG_SAFETY_ARMED | mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
                    4,  # ArduSub GUIDED
                    mavlink2.MAV_STATE_ACTIVE,
                )
                lat, lon = global_of(0.0, 0.0)
                ap.gps_global_origin_send(lat, lon, 0)
            ap.attitude_send(tb, 0.0, 0.0, yaw, 0.0, 0.0, 0.0)
            ap.local_position_ned_send(tb, n, e, 1.0, vn, ve, 0.0)
            if t > 1.0 and upload["state"] == "idle":
                gcs.mission_count_send(1, 191, 2, mavlink2.MAV_MISSION_TYPE_MISSION)
                upload["state"] = "sent"
                start = (n, e)
            k += 1
        r, _, _ = select.select([master], [], [], max(0.0, next_tick - time.time()))
        if not r:
            continue
        try:
            data = os.read(master, 4096)
        except OSError:
            break
        for m in rx.parse_buffer(data) or []:
            name = m.get_type()
            if name == "BAD_DATA":
                seen["bad"] += 1
            elif name == "SET_POSITION_TARGET_LOCAL_NED":
                seen["setpoints"] += 1
                target = (m.vx, m.vy, m.yaw, time.time())
                seen["last_setpoint"] = [m.vx, m.vy, m.yaw, n, e]
                seen["type_masks"].append(m.type_mask)
                seen["frames"].append(m.coordinate_frame)
                if math.hypot(m.vx, m.vy) > 0.05:
                    seen["setpoints_moving"] += 1
                    if seen["first_moving_setpoint"] is None:
                        seen["first_moving_setpoint"] = [m.vx, m.vy, m.yaw, n, e]
            elif name == "STATUSTEXT":
                seen["statustext"].append(m.text)
            elif name == "HEARTBEAT" and m.get_srcComponent() == 191:
                seen["heartbeats"] += 1
            elif name == "OBSTACLE_DISTANCE":
                seen["obstacle_distance"] = {
                    "distances": list(m.distances),
                    "min": m.min_distance,
                    "max": m.max_distance,
                    "increment": m.increment,
                    "increment_f": m.increment_f,
                    "frame": m.frame,
                    "yaw": yaw,
                    "at": [n, e],
                }
            elif name == "MISSION_REQUEST_INT":
                seen["mission_requests"].append(m.seq)
                if m.seq == 0:
                    gcs.mission_item_int_send(
                        1, 191, 0, mavlink2.MAV_FRAME_LOCAL_NED,
                        mavlink2.MAV_CMD_NAV_WAYPOINT, 0, 1, 0, 1.0, 0, 0,
                        int(WP1[0] * 1e4), int(WP1[1] * 1e4), 0.0,
                        mavlink2.MAV_MISSION_TYPE_MISSION)
                elif m.seq == 1:
                    lat, lon = global_of(*WP2)
                    gcs.mission_item_int_send(
                        1, 191, 1, mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
                        mavlink2.MAV_CMD_NAV_WAYPOINT, 0, 1, 0, 1.0, 0, 0,
                        lat, lon, 0.0, mavlink2.MAV_MISSION_TYPE_MISSION)
            elif name == "MISSION_ACK":
                seen["mission_ack"] = m.type
                seen["mission_ack_at"] = [n, e]
    seen["final"] = [n, e]
    seen["start"] = list(start) if start else None
    print(json.dumps(seen), flush=True)


if __name__ == "__main__":
    sys.exit(main())
