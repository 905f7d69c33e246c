"""Input and output: scene files (`scene_file`), reports (`report`), figures (`plot`),
run directories (`rundir`) and progress display (`progress`)."""
