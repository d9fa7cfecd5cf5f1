Feature: Process-image layouts
  11-bit: COB ID word (bit 0-3 length, bit 4 RTR, bit 5-15 identifier) and 8
  data bytes. 29-bit: length, COB ID (bit 0-28 identifier, bit 30 RTR, bit 31
  29-bit format) and 8 data bytes. Little-endian, packed. (000/001 §6, 003)

  @base11 @LAY-11-001 @LAY-11-002 @LAY-11-003 @LAY-11-004 @LAY-GEN-003 @LAY-11-005
  Scenario Outline: The 11-bit COB ID word in the input image
    Given the interface is set up for 11-bit messages with 4 slots
    When node 0x01 transmits <identifier> with data <data>
    And a cycle passes
    Then Inputs.RxMessage[0] begins with <word>

    Examples:
      | identifier | data                    | word                          |
      | 0x318      | 01 02 03 04 05 06 07 08 | 08 63 01 02 03 04 05 06 07 08 |
      | 0x718      | 01 02 03 04 05 06 07 08 | 08 E3 01 02 03 04 05 06 07 08 |
      | 0x1CD      | AA BB                   | A2 39 AA BB                   |
      | 0x1ED      |                         | A0 3D                         |
      | 0x000      | FF                      | 01 00 FF                      |

  @base11 @LAY-11-003
  Scenario: A remote request in the 11-bit word sets bit 4
    Given the interface is set up for 11-bit messages with 4 slots
    When a node transmits a remote request for 0x718 with length 2
    And a cycle passes
    Then Inputs.RxMessage[0] begins with 12 E3

  @base11 @LAY-11-003
  Scenario: The PLC's remote request goes on the bus as one
    Given the interface is set up for 11-bit messages with 4 slots
    When the PLC sends a remote request for 0x701 with length 1
    And a cycle passes
    Then the last frame on the bus is standard and a remote request for 1 bytes

  @ext29 @LAY-29-001 @LAY-29-002 @LAY-29-003 @LAY-29-005 @LAY-GEN-003
  Scenario Outline: The 29-bit message in the input image
    Given the interface is set up for 29-bit messages with 4 slots
    When a node transmits the 29-bit <identifier> with data <data>
    And a cycle passes
    Then Inputs.RxMessage[0] begins with <bytes>

    Examples:
      | identifier | data     | bytes                         |
      | 0x12345678 | AA BB CC | 03 00 78 56 34 92 AA BB CC    |
      | 0x00000001 |          | 00 00 01 00 00 80             |
      | 0x1FFFFFFF | 01       | 01 00 FF FF FF 9F 01          |

  @ext29 @LAY-29-005 @PROF-006 @LAY-GEN-001
  Scenario: An 11-bit frame through the 29-bit interface has bit 31 clear
    Given the interface is set up for 29-bit messages with 4 slots
    When node 0x01 transmits 0x123 with data 01
    And a cycle passes
    Then Inputs.RxMessage[0] begins with 01 00 23 01 00 00 01

  @ext29 @LAY-29-004
  Scenario: A 29-bit remote request sets bit 30
    Given the interface is set up for 29-bit messages with 4 slots
    When a node transmits a remote request for 0x123 with length 8
    And a cycle passes
    Then Inputs.RxMessage[0] begins with 08 00 23 01 00 40

  @ext29 @LAY-29-005
  Scenario: The PLC's 29-bit message goes on the bus extended
    Given the interface is set up for 29-bit messages with 4 slots
    When the PLC sends the 29-bit 0x1ABCDEF with data 01
    And a cycle passes
    Then the last frame on the bus is extended

  @base11 @LAY-GEN-002 @LAY-GEN-004 @LAY-GEN-005 @LAY-GEN-007
  Scenario Outline: Image sizes follow the slot count
    Given the interface is set up for 11-bit messages with <slots> slots
    Then the output image has <outputs> bytes and the input image <inputs> before InfoData

    Examples:
      | slots | outputs | inputs |
      | 1     | 16      | 16     |
      | 4     | 46      | 46     |
      | 32    | 326     | 326    |

  @ext29 @transaction_number @timestamp @LAY-GEN-004 @LAY-GEN-006 @TS-002
  Scenario: Transaction number and time stamp lengthen the 29-bit image
    Given the interface is set up for 29-bit messages with 2 slots
    And transaction numbers are on
    And time stamps are on
    Then the output image has 38 bytes and the input image 52 before InfoData

  @fd @LAY-FD-001 @LAY-FD-002
  Scenario: The CAN FD structures are 72 and 78 bytes
    Given the interface is set up for CAN FD messages with 4 slots
    Then the output image has 294 bytes and the input image 320 before InfoData
