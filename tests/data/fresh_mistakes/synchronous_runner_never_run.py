# robot.py
from snr import *

config = Config({"robot": [TimeoutLoopFactory(seconds=1)]})
runner = SynchronousRunner("robot", config)
print("robot configured")
