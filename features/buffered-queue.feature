Feature: Buffered and Optimized CAN Queue
  The receive messages are buffered on the device (1-buffer mode); the
  Optimized CAN Queue supports only 11-bit identifiers and no filters.
  (000 §5.1.2, 003)

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

  @HS-TX-008 @base11
  Scenario: A batch the local send queue has no room for waits, and nothing is lost
    Given the interface is set up for 11-bit messages with 32 slots
    And the bus is blocked
    When the PLC sends 96 messages
    And 5 cycles pass
    Then Inputs.TxCounter is 2
    When the bus is released
    And 40 cycles pass
    Then the bus carries 96 frames
