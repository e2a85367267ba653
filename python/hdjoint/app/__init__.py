"""The application: the `hdjoint` command (cli) and the main job on built-in
data (demo)."""
