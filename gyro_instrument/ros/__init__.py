"""The only package that imports rclpy or ROS message types: conversions and thin nodes."""
