@filters @ext29
Feature: Filters
  Acceptance: identifiers forwarded to the CAN interface. Rejection: identifiers
  not forwarded. Acceptance mask: identifiers selected bit by bit. Example for
  29-bit identifiers: only 0x400 … 0x700 reach the interface. (000/001 §7, G7)

  @FLT-009 @FLT-001 @FLT-002 @FLT-004
  Scenario Outline: The manual's filter example forwards exactly 0x400 to 0x700
    Given the interface is set up for 29-bit messages with 4 slots
    And the filter table
      | action | kind  | first      | second     |
      | reject | range | 0x00000000 | 0x000003FF |
      | accept | range | 0x00000400 | 0x00000700 |
      | reject | range | 0x00000701 | 0x1FFFFFFF |
    When a node transmits the 29-bit <identifier> with data 01
    And 2 cycles pass
    Then the PLC has received <messages> messages

    Examples:
      | identifier | messages |
      | 0x00000000 | 0        |
      | 0x000003FF | 0        |
      | 0x00000400 | 1        |
      | 0x00000555 | 1        |
      | 0x00000700 | 1        |
      | 0x00000701 | 0        |
      | 0x1FFFFFFF | 0        |

  @FLT-005
  Scenario Outline: The first matching row decides
    Given the interface is set up for 29-bit messages with 4 slots
    And the filter table
      | action | kind  | first | second |
      | accept | range | 0x100 | 0x1FF  |
      | reject | range | 0x000 | 0x7FF  |
      | accept | mask  | 0x400 | 0x700  |
    When node 0x01 transmits <identifier> with data 01
    And 2 cycles pass
    Then the PLC has received <messages> messages

    Examples:
      | identifier | messages |
      | 0x150      | 1        |
      | 0x450      | 0        |
      | 0x250      | 0        |

  @FLT-003
  Scenario Outline: An acceptance mask selects identifiers bit by bit
    Given the interface is set up for 29-bit messages with 4 slots
    And the filter table
      | action | kind | first | second |
      | accept | mask | 0x180 | 0x780  |
    When node 0x01 transmits <identifier> with data 01
    And 2 cycles pass
    Then the PLC has received <messages> messages

    Examples:
      | identifier | messages |
      | 0x180      | 1        |
      | 0x1FF      | 1        |
      | 0x17F      | 0        |
      | 0x200      | 0        |

  @FLT-006
  Scenario: Without a matching row a table with acceptance rows holds a frame back
    Given the interface is set up for 29-bit messages with 4 slots
    And the filter table
      | action | kind  | first | second |
      | accept | range | 0x100 | 0x1FF  |
    When node 0x01 transmits 0x300 with data 01
    And 2 cycles pass
    Then the PLC has received 0 messages

  @FLT-006
  Scenario: Without a matching row a table of rejections lets a frame through
    Given the interface is set up for 29-bit messages with 4 slots
    And the filter table
      | action | kind  | first | second |
      | reject | range | 0x100 | 0x1FF  |
    When node 0x01 transmits 0x300 with data 01
    And 2 cycles pass
    Then the PLC has received 1 message

  @FLT-008
  Scenario: No filters, everything arrives
    Given the interface is set up for 29-bit messages with 4 slots
    When node 0x01 transmits 0x300 with data 01
    And a node transmits the 29-bit 0x1ABCDEF with data 02
    And 2 cycles pass
    Then the PLC has received 2 messages

  @FLT-007
  Scenario: An 11-bit and a 29-bit identifier of one value are filtered alike
    Given the interface is set up for 29-bit messages with 4 slots
    And the filter table
      | action | kind  | first | second |
      | accept | range | 0x400 | 0x4FF  |
    When node 0x01 transmits 0x450 with data 01
    And a node transmits the 29-bit 0x450 with data 02
    And 2 cycles pass
    Then the PLC has received 2 messages

  @FLT-010
  Scenario: A range that runs backwards is refused
    Given the interface is set up for 29-bit messages with 4 slots
    And the filter table
      | action | kind  | first | second |
      | accept | range | 0x700 | 0x400  |
    Then the device refuses the configuration
