"""What the headless LinuxCNC displays (driver.py, program_driver.py) share: LinuxCNC's status
and command channels, waiting for a condition, and bringing the machine on and homed. Runs
under Debian's /usr/bin/python3 (the linuxcnc module), imported from the display's folder."""

import time

import linuxcnc

status, command = linuxcnc.stat(), linuxcnc.command()


def wait(condition, what, timeout=30.0, period=0.02):
    """Poll the status every ``period`` s until ``condition()``; TimeoutError naming ``what``."""
    end = time.time() + timeout
    while time.time() < end:
        status.poll()
        if condition():
            return
        time.sleep(period)
    raise TimeoutError(f"no {what} in {timeout:g} s")


def power_on_and_home():
    """Out of estop, machine on, manual mode, every joint homed."""
    wait(lambda: True, "status")
    command.state(linuxcnc.STATE_ESTOP_RESET)
    command.state(linuxcnc.STATE_ON)
    wait(lambda: status.task_state == linuxcnc.STATE_ON, "machine on")
    command.mode(linuxcnc.MODE_MANUAL)
    command.wait_complete()
    command.home(-1)
    wait(lambda: all(status.homed[:status.joints]), "homing")
