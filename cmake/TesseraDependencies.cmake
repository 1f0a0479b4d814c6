# Every dependency is a Debian 12 package (scripts/setup installs them); nothing is
# downloaded at configure or build time.
find_package(Eigen3 3.4 REQUIRED NO_MODULE)   # libeigen3-dev
find_package(TBB REQUIRED)                    # libtbb-dev (oneTBB 2021)
find_package(METIS REQUIRED)                  # libmetis-dev, see FindMETIS.cmake
