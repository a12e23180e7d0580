#!/usr/bin/env python3
"""Python modules and package folders of umbra's ROS 1 message packages.

rostopic, rosservice, rosmsg and rospy load a message or service type by
finding its package with rospack (a folder with a package.xml on
ROS_PACKAGE_PATH, /usr/share included) and importing PACKAGE.msg or
PACKAGE.srv. Debian has Python packages for its own message packages
(python3-sensor-msgs, ...) but none for octomap_msgs, and umbra_msgs is
umbra's, so `rostopic echo /octomap_binary` and `rosservice call
/umbra_server/clear_bbx` failed with "Cannot load message class" and
"Unable to load type". This generates, with Debian's genpy (python3-genpy),
for each package named before `--`:

  OUTPUT_DIR/python/PACKAGE/{msg,srv}/_NAME.py and their __init__.py
  OUTPUT_DIR/share/PACKAGE/package.xml and copies of its msg/ and srv/ files

usage: generate_python_messages.py OUTPUT_DIR VERSION PACKAGE:SHARE_DIR... -- DEPENDENCY:SHARE_DIR...
The dependencies (std_msgs, geometry_msgs, ...) are only searched for the
types the packages use. OUTPUT_DIR/setup.sh (written by CMake) puts both
folders on the paths.
"""
import glob
import os
import shutil
import sys

import genmsg.command_line
import genpy.generate_initpy
import genpy.generator

PACKAGE_XML = """<?xml version="1.0"?>
<!-- Written by umbra's ros/generate_python_messages.py: the definitions umbra_server uses, found by rospack. -->
<package format="2">
  <name>{name}</name>
  <version>{version}</version>
  <description>{name} message and service definitions as umbra builds them</description>
  <maintainer email="umbra@umbra.invalid">umbra</maintainer>
  <license>BSD</license>
  <buildtool_depend>catkin</buildtool_depend>
  <exec_depend>message_runtime</exec_depend>
  <exec_depend>std_msgs</exec_depend>
  <exec_depend>geometry_msgs</exec_depend>
</package>
"""


def generate(package, share, output_dir, version, search_path):
    python_dir = os.path.join(output_dir, 'python', package)
    share_dir = os.path.join(output_dir, 'share', package)
    os.makedirs(python_dir, exist_ok=True)
    genpy.generate_initpy.write_module(python_dir, [])
    for kind, generator in (('msg', genpy.generator.MsgGenerator()), ('srv', genpy.generator.SrvGenerator())):
        files = sorted(glob.glob(os.path.join(share, kind, '*.' + kind)))
        if not files:
            continue
        out = os.path.join(python_dir, kind)
        if generator.generate_messages(package, files, out, search_path) != 0:
            sys.exit('generate_python_messages.py: genpy failed on %s/%s' % (package, kind))
        genpy.generate_initpy.write_modules(out)
        os.makedirs(os.path.join(share_dir, kind), exist_ok=True)
        for path in files:
            shutil.copyfile(path, os.path.join(share_dir, kind, os.path.basename(path)))
    with open(os.path.join(share_dir, 'package.xml'), 'w') as f:
        f.write(PACKAGE_XML.format(name=package, version=version))


def main(argv):
    if len(argv) < 4 or '--' not in argv:
        sys.exit(__doc__)
    output_dir, version = argv[1], argv[2]
    split = argv.index('--')
    packages = [spec.split(':', 1) for spec in argv[3:split]]
    dependencies = [spec.split(':', 1) for spec in argv[split + 1:]]
    search_path = genmsg.command_line.includepath_to_dict(
        ['%s:%s' % (package, os.path.join(share, 'msg')) for package, share in packages + dependencies])
    for package, share in packages:
        generate(package, share, output_dir, version, search_path)


if __name__ == '__main__':
    main(sys.argv)
