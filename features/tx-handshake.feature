@base11
Feature: Tx handshake
  Outputs.TxCounter is set +1 when data are to be sent; NoOfTxMessages says
  how many messages of the buffer go. The device checks whether TxCounter
  has changed and acknowledges by setting Inputs.TxCounter to it.
  (000/001 §6, 003 "Buffered CAN Queue")

  Background:
    Given the interface is set up for 11-bit messages with 4 slots

  @HS-TX-001 @HS-TX-002 @HS-TX-007 @ERR-R5
  Scenario: The PLC hands over three messages and sees them acknowledged
    When the PLC sends 3 messages
    And a cycle passes
    Then Inputs.TxCounter is 1
    And the bus carries 0x100, 0x101, 0x102 in that order

  @HS-TX-007
  Scenario: The device acknowledges when it accepts, not when the bus has sent
    Given the bus is blocked
    When the PLC sends 2 messages
    And a cycle passes
    Then Inputs.TxCounter is 1
    And the bus carries nothing
    When the bus is released
    Then the bus carries 0x100, 0x101 in that order

  @HS-TX-003
  Scenario: Any change of the TxCounter counts, not only +1
    When the PLC sends 1 message
    And the PLC writes Outputs.TxCounter = 7
    And a cycle passes
    Then Inputs.TxCounter is 7
    And the bus carries 1 frame

  @HS-TX-005
  Scenario: The counters wrap from 65535 to 0
    When the PLC sends 1 message
    And the PLC writes Outputs.TxCounter = 65535
    And a cycle passes
    And the PLC sends 1 message
    And 2 cycles pass
    Then Inputs.TxCounter is 0
    And the bus carries 2 frames

  @HS-TX-009
  Scenario Outline: NoOfTxMessages says how many slots are sent
    When the PLC sends <n> messages
    And 3 cycles pass
    Then the bus carries <n> frames

    Examples:
      | n |
      | 1 |
      | 2 |
      | 4 |

  @HS-TX-011 @HS-TX-006 @HS-TX-004
  Scenario: More messages than slots go in several cycles, in order
    When the PLC sends 6 messages
    And 4 cycles pass
    Then the bus carries 0x100, 0x101, 0x102, 0x103, 0x104, 0x105 in that order
