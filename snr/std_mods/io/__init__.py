"""Input and output: console, recorder, replayer, controller."""
