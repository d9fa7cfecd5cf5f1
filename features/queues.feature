Feature: Buffered, Optimized and Fast CAN Queue
  Fast CAN Queue: no receive messages are buffered on the EL6751 and they need
  not be acknowledged; the EL6751 counts RxCounter up when new messages were
  received. Optimized CAN Queue: received messages are buffered. Both support
  only 11-bit identifiers and no filters. (000 §5.1, 003)

  @fast_queue @FQ-001 @FQ-002 @base11
  Scenario: The Fast CAN Queue delivers without waiting for the acknowledge
    Given the interface is set up for 11-bit messages with 4 slots
    And the Fast CAN Queue
    When node 0x12 transmits 0x181 with data 01
    And a cycle passes
    And node 0x12 transmits 0x182 with data 02
    And the PLC is busy for 1 cycle
    Then Inputs.RxCounter is 2
    And Inputs.NoOfRxMessages is 1

  @fast_queue @FQ-004 @base11
  Scenario: In the Fast CAN Queue what does not fit one cycle is lost
    Given the interface is set up for 11-bit messages with 4 slots
    And the Fast CAN Queue
    When other nodes transmit 7 frames
    And 3 cycles pass
    Then the PLC has received 4 messages

  @fast_queue @FQ-003 @base11
  Scenario: The Fast CAN Queue sends like the buffered queue
    Given the interface is set up for 11-bit messages with 4 slots
    And the Fast CAN Queue
    When the PLC sends 3 messages
    And 2 cycles pass
    Then Inputs.TxCounter is 1
    And the bus carries 0x100, 0x101, 0x102 in that order

  @optimized_queue @BQ-001 @base11
  Scenario: The Optimized CAN Queue buffers until the PLC has read
    Given the interface is set up for 11-bit messages with 2 slots
    And the Optimized CAN Queue
    When other nodes transmit 5 frames
    And 4 cycles pass
    Then the PLC has received 5 messages

  @BQ-003 @PROF-003
  Scenario Outline: Fast and Optimized CAN Queue refuse 29-bit messages
    Given the interface is set up for 29-bit messages with 4 slots
    And the <queue> CAN Queue
    Then the device refuses the configuration

    @fast_queue
    Examples: Fast
      | queue |
      | Fast  |

    @optimized_queue
    Examples: Optimized
      | queue     |
      | Optimized |

  @BQ-005 @base11 @fast_queue
  Scenario: The Fast CAN Queue has no transaction number
    Given the interface is set up for 11-bit messages with 4 slots
    And the Fast CAN Queue
    And transaction numbers are on
    Then the device refuses the configuration

  @BQ-004 @base11 @fast_queue
  Scenario: The Fast CAN Queue takes no filters
    Given the interface is set up for 11-bit messages with 4 slots
    And the Fast CAN Queue
    And the filter table
      | action | kind  | first | second |
      | accept | range | 0x100 | 0x1FF  |
    Then the device refuses the configuration
