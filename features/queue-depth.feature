Feature: Local Rx queue depth per device
  The CCAT CAN masters keep 512 messages, the EL6751 150 (RxMessages). (000 §4)
  A flood the PLC does not read fills the local memory: what it holds is its
  depth, on every profile of the device it binds.

  @el6751 @ext29 @RXQ-001 @RXQ-003 @RXQ-004
  Scenario: The EL6751 keeps 150 messages while the PLC does not read
    Given the interface is set up for 29-bit messages with 32 slots
    When other nodes transmit 200 frames
    And the PLC is busy for 1 cycle
    And 40 cycles pass
    Then the PLC has received 150 messages

  @ccat @ext29 @RXQ-002 @RXQ-003 @RXQ-004
  Scenario: A CCAT master keeps 512 messages while the PLC does not read
    Given the interface is set up for 29-bit messages with 32 slots
    When other nodes transmit 600 frames
    And the PLC is busy for 1 cycle
    And 40 cycles pass
    Then the PLC has received 512 messages
