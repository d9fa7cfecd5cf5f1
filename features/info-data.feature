@info_data @fd
Feature: InfoData
  The FC532x / CX-M530 report the CAN status, the bit timing and the error
  counters in InfoData. (000/001 §8.3.3)

  Background:
    Given the interface is set up for CAN FD messages with 4 slots

  @INFO-001 @INFO-002 @INFO-005 @INFO-006
  Scenario: Bus off shows in the status and stops the CAN core
    When the controller reports bus off with 7 CRC errors and a transmit error counter of 255
    And a cycle passes
    Then InfoData[0] is 0x01
    And InfoData[9] is 7
    And InfoData[14] is 255
    And InfoData[11] is 0

  @INFO-002 @INFO-006
  Scenario Outline: Status bits
    When the controller reports <state> with 0 CRC errors and a transmit error counter of 0
    And a cycle passes
    Then InfoData[0] is <word>

    Examples:
      | state         | word |
      | error passive | 0x06 |
      | warning limit | 0x0C |
      | bus idle      | 0x44 |

  @INFO-005 @INFO-007
  Scenario: The receive FIFO counts what waits for the PLC
    When other nodes transmit 7 frames
    And the PLC is busy for 2 cycles
    Then InfoData[6] is 3

  @INFO-003 @INFO-004
  Scenario: The bit timing and the transceiver delay
    Given the arbitration bit timing jump width 1, time A 13, time B 2, prescaler 5
    When the controller reports a transceiver delay of 9 time quanta
    And a cycle passes
    Then InfoData[1] is 0x05020D01
    And InfoData[3] is 9
