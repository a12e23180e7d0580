# Finds Debian 12's ROS 1 packages (ros_comm 1.15) for ros/: headers,
# libraries, the C++ message generator and roscore. Plain find_path /
# find_library on purpose: the packages' catkin CMake files run Python at
# configure time and change global settings (testing, GTest), which umbra's
# build must not inherit.
#
# Sets UMBRA_ROS_FOUND, UMBRA_ROS_MISSING (what was not found, for the
# message), the imported target umbra_ros_deps (include dirs and libraries),
# UMBRA_ROS_PYTHON, UMBRA_GENCPP_TEMPLATES, UMBRA_ROS_MSG_PACKAGES
# (package:share-folder of every message package whose headers umbra
# generates) and UMBRA_ROSCORE (for the loopback test). The Debian packages are listed in
# scripts/common.sh.

set(UMBRA_ROS_MISSING "")

# Headers, and the folder each is found in (Debian puts some in ament-style sub-folders).
set(_umbra_ros_headers
  ros/ros.h tf2_ros/transform_listener.h tf2_ros/message_filter.h message_filters/subscriber.h
  rosbag/bag.h rosbag/view.h XmlRpcValue.h pluginlib/class_loader.hpp class_loader/class_loader.hpp
  rcutils/types.h rcpputils/filesystem_helper.hpp ament_index_cpp/get_package_prefix.hpp)
set(_umbra_ros_include_dirs "")
foreach(_header IN LISTS _umbra_ros_headers)
  string(MAKE_C_IDENTIFIER "UMBRA_ROS_HEADER_${_header}" _var)
  find_path(${_var} ${_header} PATH_SUFFIXES xmlrpcpp pluginlib class_loader rcutils rcpputils ament_index_cpp)
  if(${_var})
    list(APPEND _umbra_ros_include_dirs ${${_var}})
  else()
    list(APPEND UMBRA_ROS_MISSING ${_header})
  endif()
endforeach()
list(REMOVE_DUPLICATES _umbra_ros_include_dirs)

set(_umbra_ros_libraries
  roscpp rosconsole roscpp_serialization rostime cpp_common xmlrpcpp tf2 tf2_ros message_filters
  rosbag rosbag_storage console_bridge boost_system boost_thread)
set(_umbra_ros_library_paths "")
foreach(_library IN LISTS _umbra_ros_libraries)
  find_library(UMBRA_ROS_LIB_${_library} ${_library})
  if(UMBRA_ROS_LIB_${_library})
    list(APPEND _umbra_ros_library_paths ${UMBRA_ROS_LIB_${_library}})
  else()
    list(APPEND UMBRA_ROS_MISSING lib${_library})
  endif()
endforeach()

# The message generator's templates (python3-gencpp) and the message definitions of the packages umbra's
# ROS code includes (ros-*-msgs; see ros/generate_messages.py for why they are generated again).
find_path(UMBRA_GENCPP_TEMPLATES msg.h.template PATHS /usr/share/gencpp NO_DEFAULT_PATH)
if(NOT UMBRA_GENCPP_TEMPLATES)
  list(APPEND UMBRA_ROS_MISSING "gencpp templates")
endif()
set(UMBRA_ROS_MSG_PACKAGES "")
foreach(_package std_msgs geometry_msgs sensor_msgs visualization_msgs tf2_msgs actionlib_msgs std_srvs nav_msgs)
  find_path(UMBRA_ROS_SHARE_${_package} package.xml PATHS /usr/share/${_package} NO_DEFAULT_PATH)
  if(UMBRA_ROS_SHARE_${_package})
    list(APPEND UMBRA_ROS_MSG_PACKAGES ${_package}:${UMBRA_ROS_SHARE_${_package}})
  else()
    list(APPEND UMBRA_ROS_MISSING "${_package} message definitions (/usr/share/${_package})")
  endif()
endforeach()

# A Python that can run gen_cpp.py: Debian's /usr/bin/python3 first (a python3 earlier on PATH, e.g. pyenv's,
# usually lacks the Debian modules).
if(NOT UMBRA_ROS_PYTHON)
  find_program(_umbra_path_python3 python3)
  foreach(_python /usr/bin/python3 ${_umbra_path_python3})
    if(EXISTS ${_python})
      execute_process(COMMAND ${_python} -c "import genmsg, gencpp, em" RESULT_VARIABLE _result OUTPUT_QUIET ERROR_QUIET)
      if(_result EQUAL 0)
        set(UMBRA_ROS_PYTHON ${_python} CACHE FILEPATH "Python 3 with genmsg, gencpp and empy (for ROS message headers)")
        break()
      endif()
    endif()
  endforeach()
endif()
if(NOT UMBRA_ROS_PYTHON)
  list(APPEND UMBRA_ROS_MISSING "python3 with genmsg/gencpp/em")
endif()

find_program(UMBRA_ROSCORE roscore)

if(UMBRA_ROS_MISSING)
  set(UMBRA_ROS_FOUND FALSE)
else()
  set(UMBRA_ROS_FOUND TRUE)
  add_library(umbra_ros_deps INTERFACE IMPORTED GLOBAL)  # GLOBAL: tests/ros links it too
  # SYSTEM: ROS headers do not pass umbra's warning flags (old-style casts, shadowing).
  set_target_properties(umbra_ros_deps PROPERTIES
    INTERFACE_SYSTEM_INCLUDE_DIRECTORIES "${_umbra_ros_include_dirs}"
    INTERFACE_INCLUDE_DIRECTORIES "${_umbra_ros_include_dirs}"
    INTERFACE_LINK_LIBRARIES "${_umbra_ros_library_paths}")
endif()
