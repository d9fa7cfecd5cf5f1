@once
Feature: Local Rx queue depth per device
  The CCAT CAN masters keep 512 messages, the EL6751 150 (RxMessages). (000 §4)

  @RXQ-001 @RXQ-002 @RXQ-003
  Scenario Outline: What the local memory holds while the PLC does not read
    Given the device profile <profile>
    And the interface is set up for 29-bit messages with 32 slots
    When other nodes transmit <sent> frames
    And the PLC is busy for 1 cycle
    And 40 cycles pass
    Then the PLC has received <kept> messages

    Examples:
      | profile    | sent | kept |
      | el6751-mdp | 200  | 150  |
      | ccat       | 600  | 512  |
