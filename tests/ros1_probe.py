"""Run by Debian's /usr/bin/python3 (rospy, tf2_ros) while `roslaunch <robot> display.launch` runs:
prints, as JSON, /robot_description, one /joint_states message and every link's transform
from the root link (tf2_ros.Buffer; Debian's `tf_echo` is broken, docs/libraries.md, section 10).
A robot without a joint joint_state_publisher moves (a drone's one link, a sensor) has no
/joint_states message (it publishes none empty): its joint states are {}.

    python3 ros1_probe.py ROOT LINK... > result.json
"""

import json
import sys
import time
import xml.etree.ElementTree as ET

import rospy
import tf2_ros
from sensor_msgs.msg import JointState


def main():
    root, links = sys.argv[1], sys.argv[2:]
    rospy.init_node("robotkit_probe", anonymous=True, disable_signals=True)
    deadline = time.monotonic() + 30
    while not rospy.has_param("/robot_description"):
        if time.monotonic() > deadline:
            raise SystemExit("no /robot_description parameter")
        time.sleep(0.2)
    description = rospy.get_param("/robot_description")
    # joint_state_publisher's own rule (its free and mimic joints): any joint but these
    moved = [j for j in ET.fromstring(description).findall("joint") if j.get("type") not in ("fixed", "floating", "planar")]
    js = rospy.wait_for_message("/joint_states", JointState, timeout=30) if moved else JointState()
    buf = tf2_ros.Buffer()
    tf2_ros.TransformListener(buf)
    tf = {}
    for link in links:
        t = buf.lookup_transform(root, link, rospy.Time(0), rospy.Duration(30)).transform
        tf[link] = [t.translation.x, t.translation.y, t.translation.z,
                    t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w]
    print(json.dumps({"description": description, "joint_states": dict(zip(js.name, js.position)), "tf": tf}))


if __name__ == "__main__":
    main()
