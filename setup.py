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
    # the scenes, and the estimate's JSON Schema (tools/gen_estimate_docs.py writes it from the typed records)
    package_data={"gyro_instrument.scenes": ["*.yaml"], "gyro_instrument.estimators": ["estimate.schema.json"],
                  "gyro_instrument.ros": ["fastdds_profile.xml"]},
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml"]),
        (f"share/{PACKAGE}/scenes", glob("gyro_instrument/scenes/*.yaml")),
        (f"share/{PACKAGE}/msg_docs", glob("msg_docs/*.md")),
        (f"share/{PACKAGE}/docs/formats", glob("docs/formats/*.md")),
    ],
    python_requires=">=3.10",
    install_requires=["numpy>=1.24", "scipy>=1.10", "numba>=0.60", "pyyaml>=6", "pyarrow>=12"],
    extras_require={
        "ros": ROS,
        "test": ROS + ["pytest>=7", "pytest-xdist>=3.5", "hypothesis>=6", "rosbags>=0.10", "colcon-common-extensions", "matplotlib>=3.6",
                       "dask[distributed]>=2023.1", "pynmea2==1.19.0",
                       # validates every estimate JSON against the shipped schema (tests/test_estimate_schema.py;
                       # draft 2020-12's unevaluatedProperties needs >= 4.0, its referencing library >= 4.18)
                       "jsonschema>=4.18"],
        "plot": ["matplotlib>=3.6"],
        "cluster": ["dask[distributed]>=2023.1"],
    },
    zip_safe=True,
    maintainer="gyro_instrument developers",
    maintainer_email="dev@gyro-instrument.invalid",
    description="Gyrocompass and Foucault pendulum on the rotating Earth: simulators, estimator, MCAP recording.",
    license="Apache-2.0",
    entry_points={
        # plug-ins (gyro_instrument/core/plugins.py): the shipped instruments, effects and measurement
        # kinds are entry points of the groups a package extends (docs/extending.md)
        "gyro_instrument.instruments": [
            "plane_gyroscope = gyro_instrument.instruments.plane_gyroscope.instrument:PlaneGyroscope",
            "spherical_pendulum = gyro_instrument.instruments.pendulum.instrument:SphericalPendulum",
            "compound_pendulum = gyro_instrument.instruments.pendulum.instrument:CompoundPendulum",
            "free_gyroscope = gyro_instrument.instruments.free_gyroscope.instrument:FreeGyroscope",
            "puiseux_body = gyro_instrument.instruments.puiseux.instrument:PuiseuxBody",
            "gimbal_gyroscope = gyro_instrument.instruments.gimbal.instrument:GimbalGyroscope",
            "rate_gyro = gyro_instrument.instruments.rate_gyro.instrument:RateGyro",
            "marine_gyrocompass = gyro_instrument.instruments.marine_gyrocompass:MarineGyrocompass",
        ],
        "gyro_instrument.effects": [
            "earth_rotation = gyro_instrument.effects.earth_rotation:EarthRotation",
            "centrifugal = gyro_instrument.effects.centrifugal:Centrifugal",
            "finite_amplitude = gyro_instrument.effects.finite_amplitude:FiniteAmplitude",
            "ring_inertia = gyro_instrument.effects.ring_inertia:RingInertia",
            "spin_decay = gyro_instrument.effects.spin_decay:SpinDecay",
            "pivot_damping = gyro_instrument.effects.pivot_damping:PivotDamping",
            "air_drag = gyro_instrument.effects.air_drag:AirDrag",
            "tape_torsion = gyro_instrument.effects.tape_torsion:TapeTorsion",
            "tape_drift = gyro_instrument.effects.tape_drift:TapeDrift",
        ],
        "gyro_instrument.measurements": [
            "gyro = gyro_instrument.estimators.kinds:SwingKind",
            "pendulum = gyro_instrument.estimators.kinds:PlaneKind",
            "azimuth = gyro_instrument.estimators.kinds:AzimuthKind",
            "rate_azimuth = gyro_instrument.estimators.rate_gyro_kind:RateAzimuthKind",
            "compass = gyro_instrument.estimators.compass_kind:CompassKind",
        ],
        "console_scripts": [
            "gyro-instrument = gyro_instrument.ros.cli:main",
            "gyrocompass_sim = gyro_instrument.ros.main:gyrocompass_sim",
            "pendulum_sim = gyro_instrument.ros.main:pendulum_sim",
            "top_sim = gyro_instrument.ros.main:top_sim",
            "marine_gyrocompass = gyro_instrument.ros.main:marine_gyrocompass",
            "estimator = gyro_instrument.ros.main:estimator",
            "recorder = gyro_instrument.ros.main:recorder",
            "player = gyro_instrument.ros.main:player",
        ],
    },
)
