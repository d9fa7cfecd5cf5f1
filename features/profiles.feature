@once
Feature: Device profiles and what they refuse
  Choose only modes your hardware supports (000 §3); the feature matrix of
  000/001 §2 and its footnotes say which. Each scenario names its profile.

  @PROF-001 @PROF-002 @PROF-006 @PROF-007 @PROF-009
  Scenario Outline: Which frame formats a device offers
    Given the device profile <profile>
    And the interface is set up for <format> messages with 4 slots
    Then the device <verdict> the configuration

    Examples:
      | profile              | format  | verdict |
      | el6751-legacy        | 11-bit  | accepts |
      | el6751-legacy        | CAN FD  | refuses |
      | ccat                 | 11-bit  | refuses |
      | ccat                 | 29-bit  | accepts |
      | fc510x-before-fw2.14 | 29-bit  | refuses |
      | fc510x               | 29-bit  | accepts |
      | fc532x               | CAN FD  | accepts |
      | cx1500-m510          | CAN FD  | refuses |

  @PROF-001 @PROF-002
  Scenario Outline: Which CAN queues a device offers
    Given the device profile <profile>
    And the interface is set up for 11-bit messages with 4 slots
    And the <queue> CAN Queue
    Then the device <verdict> the configuration

    Examples:
      | profile       | queue     | verdict |
      | el6751-mdp    | Fast      | accepts |
      | el6751-legacy | Fast      | refuses |
      | el6751-legacy | Optimized | accepts |
      | fc532x        | Optimized | refuses |

  @PROF-005 @TN-004
  Scenario Outline: The legacy mapping has the transaction number only in 29-bit mode
    Given the device profile <profile>
    And the interface is set up for <format> messages with 4 slots
    And transaction numbers are on
    Then the device <verdict> the configuration

    Examples:
      | profile       | format | verdict |
      | el6751-legacy | 11-bit | refuses |
      | el6751-legacy | 29-bit | accepts |
      | el6751-mdp    | 11-bit | accepts |

  @PROF-008 @PROF-004
  Scenario Outline: CCAT has transaction number and time stamp from firmware 1.17
    Given the device profile <profile>
    And the interface is set up for 29-bit messages with 4 slots
    And transaction numbers are on
    And time stamps are on
    Then the device <verdict> the configuration

    Examples:
      | profile            | verdict |
      | ccat-before-fw1.17 | refuses |
      | ccat               | accepts |

  @PROF-008
  Scenario Outline: CCAT has the transaction number from firmware 1.17, with or without time stamps
    Given the device profile <profile>
    And the interface is set up for 29-bit messages with 4 slots
    And transaction numbers are on
    Then the device <verdict> the configuration

    Examples:
      | profile            | verdict |
      | ccat-before-fw1.17 | refuses |
      | ccat               | accepts |

  @PROF-011 @LAY-GEN-007 @ERR-R2
  Scenario Outline: 1 to 32 slots
    Given the device profile el6751-mdp
    And the interface is set up for 11-bit messages with <slots> slots
    Then the device <verdict> the configuration

    Examples:
      | slots | verdict |
      | 0     | refuses |
      | 1     | accepts |
      | 10    | accepts |
      | 32    | accepts |
      | 33    | refuses |

  @PROF-012 @INFO-001
  Scenario Outline: Only the FC532x family reports InfoData
    Given the device profile <profile>
    And the interface is set up for 29-bit messages with 2 slots
    Then the output image has 34 bytes and the input image <inputs>

    Examples:
      | profile | inputs |
      | fc532x  | 98     |
      | ccat    | 34     |
