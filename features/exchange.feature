@base11
Feature: Process-data exchange
  With LRW, two cycles pass in the task until the increment of the TxCounter is
  confirmed; with "separate input update" the inputs are read just before the
  next task. In Fast CAN Queue mode the cycle may be started by SYNC0 and the
  first Tx message waits for SYNC1. (003)

  @PDX-001
  Scenario: LRW confirms after two task cycles
    Given the interface is set up for 11-bit messages with 4 slots
    And the process data is exchanged with LRW
    When the PLC sends 1 message
    And 4 cycles pass
    Then the PLC saw the confirmation 2 cycles after its increment

  @PDX-002 @PDX-003
  Scenario: Separate input update confirms after one
    Given the interface is set up for 11-bit messages with 4 slots
    And the process data is exchanged with separate input update
    When the PLC sends 1 message
    And 4 cycles pass
    Then the PLC saw the confirmation 1 cycle after its increment

  @distributed_clocks @fast_queue @PDX-004 @PDX-005
  Scenario: With Distributed Clocks the first message waits for SYNC1
    Given the interface is set up for 11-bit messages with 4 slots
    And the Fast CAN Queue
    And distributed clocks with SYNC1 300 µs after SYNC0
    When the PLC sends 2 messages
    And a cycle passes
    Then the bus carries 0x100, 0x101 in that order
    And the first frame of the last cycle started 300 µs after the cycle began

  @fast_queue @PDX-003
  Scenario: Without Distributed Clocks the first message starts with the cycle
    Given the interface is set up for 11-bit messages with 4 slots
    And the Fast CAN Queue
    When the PLC sends 2 messages
    And a cycle passes
    Then the first frame of the last cycle started 0 µs after the cycle began

  @distributed_clocks @PDX-005
  Scenario: Distributed Clocks only with the Fast CAN Queue
    Given the interface is set up for 11-bit messages with 4 slots
    And distributed clocks with SYNC1 300 µs after SYNC0
    Then the device refuses the configuration
