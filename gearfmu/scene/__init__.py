"""The scene: TOML reader and its [envelope]/[accuracy] sections."""
