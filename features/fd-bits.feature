Feature: CAN FD bits
  EDL selects whether an FD or a classic frame is sent, or tells what kind was
  received; BRS (printed BSR) whether the data phase switches to the higher bit
  rate; ESI the error state. (000/001 §8.3.2)

  @fd @FD-BIT-001 @FD-BIT-002 @FD-BIT-003
  Scenario Outline: EDL, BRS and ESI go on the bus as the PLC sets them
    Given the interface is set up for CAN FD messages with 4 slots
    When the PLC sends an FD message 0x321 with 16 bytes <flags>
    And a cycle passes
    Then the last frame on the bus is an FD frame <flags>

    Examples:
      | flags              |
      |                    |
      |  with BRS          |
      |  with BRS and ESI  |

  @fd @FD-BIT-001 @FD-BIT-002 @FD-BIT-003 @FD-LEN-005 @FD-001
  Scenario Outline: Received FD frames report their size and bits
    Given the interface is set up for CAN FD messages with 4 slots
    When a node transmits an FD frame 0x222 with <size> bytes <flags>
    And node 0x01 transmits 0x111 with data 01 02
    And 2 cycles pass
    Then the PLC's message 0 is an FD frame of <size> bytes <flags>
    And the PLC has received 0x111 with data 01 02

    Examples:
      | size | flags            |
      | 12   |                  |
      | 48   | with BRS         |
      | 64   | with ESI         |
      | 20   | with BRS and ESI |

  @fd @FD-BIT-001
  Scenario: A classic frame through the FD interface stays classic
    Given the interface is set up for CAN FD messages with 4 slots
    When the PLC sends 0x7E5 with data 01 02 03
    And a cycle passes
    Then the last frame on the bus is a classic frame
