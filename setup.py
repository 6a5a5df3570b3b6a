"""ament_python package gyro_instrument (also pip-installable: console scripts in bin/)."""

from glob import glob

from setuptools import find_packages, setup

PACKAGE = "gyro_instrument"

ROS = ["ros-jazzy-rclpy", "ros-jazzy-rmw-fastrtps-cpp", "ros-jazzy-common-interfaces",
       "mcap>=1.1", "mcap-ros2-support>=0.5"]

setup(
    name=PACKAGE,
    version="0.1.0",
    packages=find_packages(exclude=["tests", "tests.*"]),
    package_data={"gyro_instrument.scenes": ["*.yaml"]},
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml"]),
        (f"share/{PACKAGE}/scenes", glob("gyro_instrument/scenes/*.yaml")),
        (f"share/{PACKAGE}/msg_docs", glob("msg_docs/*.md")),
    ],
    python_requires=">=3.10",
    install_requires=["numpy>=1.24", "scipy>=1.10", "numba>=0.60", "pyyaml>=6", "pyarrow>=12"],
    extras_require={
        "ros": ROS,
        "test": ROS + ["pytest>=7", "hypothesis>=6", "rosbags>=0.10", "colcon-common-extensions", "matplotlib>=3.6",
                       "dask[distributed]>=2023.1", "pynmea2==1.19.0"],
        "plot": ["matplotlib>=3.6"],
        "cluster": ["dask[distributed]>=2023.1"],
    },
    zip_safe=True,
    maintainer="gyro_instrument developers",
    maintainer_email="dev@gyro-instrument.invalid",
    description="Gyrocompass and Foucault pendulum on the rotating Earth: simulators, estimator, MCAP recording.",
    license="Apache-2.0",
    entry_points={
        "console_scripts": [
            "gyro-instrument = gyro_instrument.ros.cli:main",
            "gyrocompass_sim = gyro_instrument.ros.main:gyrocompass_sim",
            "pendulum_sim = gyro_instrument.ros.main:pendulum_sim",
            "top_sim = gyro_instrument.ros.main:top_sim",
            "estimator = gyro_instrument.ros.main:estimator",
            "recorder = gyro_instrument.ros.main:recorder",
            "player = gyro_instrument.ros.main:player",
        ],
    },
)
