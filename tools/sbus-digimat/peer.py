"""Two roles of a local Ether-S-Bus session with digimat-saia (PyPI, 0.1.71).

    python peer.py server SECONDS   # station 10 on UDP 5050, preset memory
    python peer.py client           # station 253 on UDP 15050, reads and writes station 10

Run both in a private network namespace that has only a loopback interface (see capture.sh):
digimat can broadcast discovery requests otherwise. Our own script; see
../../docs/sbus.md ("A real capture").
"""
import logging
import sys
import time

from digimat.saia import SAIANode


def make_node(lid, port):
    quiet = logging.getLogger("saia-%d" % lid)
    quiet.setLevel(logging.WARNING)  # the default logger would try a TCP log socket
    return SAIANode(lid=lid, port=port, logger=quiet, scanner=False,
                    broadcastAddress="127.255.255.255", localIfaceIpAddr="127.0.0.1")


def server(seconds):
    srv = make_node(10, 5050)
    mem = srv.memory
    mem.registers[0].value = 0x12345678
    mem.registers[1].value = 100
    mem.registers[2].value = 0xB5C5B5C5      # B5/C5 bytes travel raw on UDP
    mem.registers[3].value = 42
    for i in range(8):
        mem.flags[i].value = (i % 3 == 0)
    for i in range(4):
        mem.inputs[i].value = (i % 2 == 1)
        mem.outputs[i].value = (i == 2)
    mem.timers[0].value = 50000
    mem.timers[1].value = 7
    mem.counters[0].value = 1234
    mem.counters[5].value = 99
    time.sleep(seconds)
    srv.stop()


def client():
    cli = make_node(253, 15050)
    pcd = cli.servers.declare("127.0.0.1", lid=10, port=5050)
    time.sleep(1)
    mem = pcd.memory
    regs = mem.registers.declareRange(0, 4)
    print("R0 =", regs[0].read(timeout=5))
    print("F0 =", mem.flags[0].read(timeout=5))
    flags = mem.flags.declareRange(0, 8)
    print("F7 =", flags[7].read(timeout=5))
    print("I1 =", mem.inputs[1].read(timeout=5))
    print("O2 =", mem.outputs[2].read(timeout=5))
    print("T0 =", mem.timers[0].read(timeout=5))
    print("C5 =", mem.counters[5].read(timeout=5))
    # writes (digimat reads each item back afterwards)
    regs[1].value = 0xB5
    mem.flags[3].value = False
    mem.flags[9].value = True
    mem.outputs[1].on()
    mem.timers[1].value = 300
    mem.counters[0].value = 4321
    time.sleep(2)
    print("R1 =", regs[1].read(timeout=5))
    print("F9 =", mem.flags[9].read(timeout=5))
    print("O1 =", mem.outputs[1].read(timeout=5))
    print("T1 =", mem.timers[1].read(timeout=5))
    print("C0 =", mem.counters[0].read(timeout=5))
    cli.stop()


if __name__ == "__main__":
    if sys.argv[1] == "server":
        server(float(sys.argv[2]))
    else:
        client()
