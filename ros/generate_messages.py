#!/usr/bin/env python3
"""C++ headers of ROS 1 messages and services, generated with Debian's gencpp.

umbra builds its ROS code as C++20. Debian 12 ships message headers made by
an older gencpp that uses std::allocator<void>::rebind, which C++20 removed;
its gencpp 0.7.0 (python3-gencpp) writes headers that use
std::allocator_traits instead. So the headers of the message packages umbra
includes are generated again from Debian's own .msg/.srv files, together with
umbra's octomap_msgs, into one folder that comes before /usr/include.

usage: generate_messages.py OUTPUT_DIR TEMPLATE_DIR PACKAGE:SHARE_DIR...
Every msg/*.msg and srv/*.srv under each SHARE_DIR is generated into
OUTPUT_DIR/PACKAGE/; all packages named are the search path for dependencies.
One process for all files (starting Python per file would cost seconds).
"""
import glob
import os
import sys

import genmsg.template_tools


def main(argv):
    if len(argv) < 4:
        sys.exit(__doc__)
    output_dir, template_dir, specs = argv[1], argv[2], argv[3:]
    packages = [spec.split(':', 1) for spec in specs]
    search_path = ['%s:%s' % (package, os.path.join(share, 'msg')) for package, share in packages]
    for package, share in packages:
        out = os.path.join(output_dir, package)
        os.makedirs(out, exist_ok=True)
        for path in sorted(glob.glob(os.path.join(share, 'msg', '*.msg')) + glob.glob(os.path.join(share, 'srv', '*.srv'))):
            genmsg.template_tools.generate_from_file(
                path, package, out, template_dir, search_path,
                {'msg.h.template': '@NAME@.h'}, {'srv.h.template': '@NAME@.h'})


if __name__ == '__main__':
    main(sys.argv)
